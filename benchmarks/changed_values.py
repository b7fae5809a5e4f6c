"""How far a rebuild moved the norms, against the uncertainty each artifact states.

    python benchmarks/changed_values.py --out docs/evidence/assembly_round_off.json

A run moves every artifact it no longer trusts to ``<name>.stale`` before rebuilding it; for each
norm artifact ``results/<scene>/N<N>/norms/<norm>.json`` that has such a predecessor, this records
the old and new value, the change (absolute and relative) and the change in units of the new
artifact's ``algebraic_error.uncertainty`` (how far round-off in ``u_h`` is stated to move it).
A ratio above 1 is a change the stated uncertainty did not cover.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def changes(results: Path) -> list[dict]:
    """One record per norm artifact with a ``.stale`` predecessor of another value, largest ratio first."""
    rows = []
    for new in sorted(results.glob("*/N*/norms/*.json")):
        old = new.with_name(new.name + ".stale")
        try:
            before, after = (json.loads(p.read_text(encoding="utf-8")) for p in (old, new))
        except (OSError, ValueError):
            continue
        change = abs(after["value"] - before["value"])
        uncertainty = (after.get("algebraic_error") or {}).get("uncertainty")
        rows.append(
            {
                "artifact": new.relative_to(results.parent).as_posix(),
                "old": before["value"],
                "new": after["value"],
                "change": change,
                "relative_change": change / abs(after["value"]) if after["value"] else None,
                "uncertainty": uncertainty,
                "change_over_uncertainty": change / uncertainty if uncertainty else None,
            }
        )
    return sorted(rows, key=lambda row: -(row["change_over_uncertainty"] or 0.0))


def summary(rows: list[dict]) -> dict:
    """Per scene: artifacts compared, those changed, the largest ratio and relative change."""
    scenes: dict[str, dict] = {}
    for row in rows:
        s = scenes.setdefault(row["artifact"].split("/")[1], {"compared": 0, "changed": 0, "max_ratio": 0.0})
        s["compared"] += 1
        s["changed"] += row["change"] > 0
        s["max_ratio"] = max(s["max_ratio"], row["change_over_uncertainty"] or 0.0)
        s["max_relative_change"] = max(s.get("max_relative_change", 0.0), row["relative_change"] or 0.0)
    return scenes


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--results", type=Path, default=ROOT / "results")
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--note", default="", help="what changed between the two runs")
    args = parser.parse_args(argv)
    rows = changes(args.results)
    args.out.write_text(
        json.dumps({"note": args.note, "scenes": summary(rows), "artifacts": rows}, indent=1) + "\n", encoding="utf-8"
    )
    print(json.dumps(summary(rows), indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
