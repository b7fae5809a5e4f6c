"""Stage ``work_precision_report``: ``work_precision.md``, the findings (``findings``) rendered
as Markdown — setup, machine and software, what the timing protocol did, the one selection rule
and the intervals, the tolerance each solver needs so that Table 1 keeps its printed digits, the
time to that accuracy, the comparisons from the same start, the ``L⁴`` EOCs of the inexact
solutions against the published ones, the exact solver's cost of accuracy, and every failure or
skip with its reason.  Every verdict is chosen by a computed condition; the prose is the template
``report.tmpl`` next to this module (``study.REPORT_TEMPLATE``, read by ``prose``), the numbers and
tables are filled in here."""

from __future__ import annotations

import functools
import math
import os
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from signorini import intervals
from signorini.formatting import fmt_factor, fmt_fit, fmt_ratio, fmt_rel, fmt_time, fmt_timed, h_label, md_table, sci_md
from signorini.pipeline.jobenv import THREAD_VARIABLES
from signorini.published import TABLE1_NORMS, label_md
from signorini.studies.work_precision.findings import COST_NORMS, findings
from signorini.studies.work_precision.selection import swept
from signorini.studies.work_precision.study import EXACT_LABEL, REPORT_TEMPLATE, tolerance_key
from signorini.timing import Protocol

if TYPE_CHECKING:
    from signorini.studies.work_precision.table import Run

# an inexact run reproduces the published EOCs *markedly better* than the exact solution when its largest
# deviation from them is below MARKEDLY times the exact one's; it *scatters* them when above SCATTERS times
MARKEDLY, SCATTERS = 0.5, 2.0
VERDICTS = {"below": "the other faster", "above": "ours faster", "tie": "tie", "undetermined": "undetermined"}


@functools.cache
def _sections(path: Path = REPORT_TEMPLATE) -> dict[str, str]:
    """The template's sections: name → text, a line ending in a backslash joined to the next."""
    parts = re.split(r"^@@ (\w+)\n", path.read_text(encoding="utf-8"), flags=re.MULTILINE)[1:]
    return {name: text.rstrip("\n").replace("\\\n", "") for name, text in zip(parts[::2], parts[1::2], strict=True)}


def prose(section: str, /, **fields: object) -> str:
    """The template's ``section`` with its ``fields`` filled in (``str.format``)."""
    return _sections()[section].format(**fields)


def _table(section: str, header: Sequence[str], rows: Sequence[Sequence[str]], align: str = "r", **fields) -> list:
    """The template's ``section`` above a Markdown table."""
    return ["", prose(section, **fields), "", md_table(header, rows, align)]


def _name(entry: Mapping, labels: Mapping[str, str]) -> str:
    """A selected run by its configuration's label and its tolerance: ``OSQP (1e-06)``."""
    return f"{labels[entry['config']]} ({entry['tol_label']})"


def _swept(runs: Sequence[Run]) -> str:
    """The swept tolerances, loosest first."""
    return ", ".join(swept([r.tol_label for r in runs if r.tol_label != EXACT_LABEL]))


def _meshes(found: Mapping) -> str:
    return ", ".join(str(N) for N in found["N"])


def _counts(counts: Mapping[str, int]) -> str:
    """Counts by status: ``failed 2, ok 10``."""
    return ", ".join(f"{k} {n}" for k, n in sorted(counts.items()))


def _protocol_text(found: Mapping, protocol: Protocol) -> str:
    p = found["protocol"]
    limit = "the cores" if protocol.max_load is None else f"{protocol.max_load:g}"
    settings = {**protocol.as_dict(), "max_load": limit, "short_time": fmt_time(p["short_s"])}
    text = [prose("protocol", **p, **settings), prose("protocol_cpu", **p, **settings)]
    if math.isfinite(p["kernel_spread"]):
        text.append(prose("kernel_spread", kernel_spread=p["kernel_spread"]))
    return " ".join(text)


def _machine_record(record: Mapping) -> str:
    """One machine record (``timing.machine_record``) in words."""
    virtual = {True: "virtualised (the CPU's hypervisor flag)", False: "no hypervisor flag"}.get(
        record.get("hypervisor"), "virtualisation not recorded"
    )
    product = f", product {record['product']}" if record.get("product") else ""
    threads = ", ".join(f"{k}={v or 'unset'}" for k, v in (record.get("threads") or {}).items())
    software = ", ".join(f"{k} {v}" for k, v in (record.get("software") or {}).items())
    return (
        f"{record.get('cores', '?')} cores ({record.get('usable_cores', '?')} usable), CPU "
        f"{record.get('cpu_model') or 'model not recorded'}, {virtual}{product}; threads {threads or 'not recorded'}; "
        f"{software or 'software versions not recorded'}"
    )


def _machine_text(found: Mapping) -> str:
    sw = found["software"]
    parts = [prose("petsc", versions=", ".join(sw["petsc"]))] if sw["petsc"] else []
    parts.append(prose("threads", variables=", ".join(f"`{v}`" for v in THREAD_VARIABLES)))
    sentence = "; ".join(parts)
    text = [prose("machine", sentence=sentence[:1].upper() + sentence[1:])]
    if sw["machines"]:
        recorded = "; ".join(f"{_machine_record(m['record'])} ({m['runs']} runs)" for m in sw["machines"])
        text.append(prose("recorded", recorded=recorded))
    if sw["unrecorded"]:
        text.append(prose("unrecorded", runs=sw["unrecorded"]))
    return " ".join(text)


def _setup(runs: Sequence[Run], found: Mapping, source: str, protocol: Protocol) -> list[str]:
    solvers = ", ".join(dict.fromkeys(r.label for r in runs))
    numbers = {"meshes": _meshes(found), "tolerances": _swept(runs), "counts": _counts(found["counts"])}
    lines = [prose("setup", source=source, solvers=solvers, **numbers), _machine_text(found)]
    if found["load"]:
        lines.append(prose("load", **found["load"]))
    lines.append(_protocol_text(found, protocol))
    if math.isfinite(found["span_s"]):
        concurrent = found["concurrent_jobs"]
        at_once = "one job" if concurrent == 1 else f"{concurrent} jobs"
        lines.append(prose("span", span=found["span_s"] / 60, job=found["job_time_s"] / 60, concurrent=at_once))
    return lines


def _rules(runs: Sequence[Run], found: Mapping) -> list[str]:
    """The selection rule and the intervals, stated once."""
    numbers = {"n_norms": len(found["table1_norms"]), "n_meshes": len(found["N"]), "meshes": _meshes(found)}
    bootstrap = {"level": intervals.LEVEL, "resamples": intervals.RESAMPLES, "seed": intervals.SEED}
    return ["", prose("rules", tolerances=_swept(runs), **numbers, **bootstrap)]


def _eoc_brief(found: Mapping) -> list[str]:
    """Whether a run at one fixed tolerance reproduces the published irregular EOCs markedly better
    than the exact solution (``MARKEDLY``), and how many scatter them (``SCATTERS``)."""
    eocs, paper_rates = list(found["eoc"]), found["paper_l4_eoc"]
    exact = next((e for e in eocs if e["tol_label"] == EXACT_LABEL), None)
    inexact = [e for e in eocs if e["tol_label"] != EXACT_LABEL and math.isfinite(e["max_dev_paper"])]
    if not (paper_rates and exact is not None and inexact):
        return []
    best = min(inexact, key=lambda e: e["max_dev_paper"])
    dev, best_dev = exact["max_dev_paper"], best["max_dev_paper"]

    def fmt(rates: Sequence[float]) -> str:
        return ", ".join(f"{r:.4f}" for r in rates)

    line = prose("eoc", paper=fmt(paper_rates), exact_eoc=fmt(exact["eoc"]), best_eoc=fmt(best["eoc"]), exact=exact,
                 best=best)
    if best_dev < MARKEDLY * dev:
        verdict = prose("eoc_close", best=best, markedly=MARKEDLY)
    else:
        closer = sum(e["max_dev_paper"] < dev for e in inexact)
        wild = sum(e["max_dev_paper"] > SCATTERS * dev for e in inexact)
        verdict = prose("eoc_far", closer=closer, inexact=len(inexact), gain=max(dev - best_dev, 0.0), wild=wild,
                        markedly=MARKEDLY, scatters=SCATTERS)
    return [line, f"  {verdict}"]


def _needed_brief(found: Mapping, labels: Mapping[str, str]) -> str:
    has = [f"{labels[c]} {tol}" for c, tol in found["needed"].items() if tol]
    none = [labels[c] for c, tol in found["needed"].items() if not tol]
    parts = ["; ".join(has) if has else prose("needed_none")]
    if none and has:
        parts.append(prose("needed_without", configs=", ".join(none)))
    norms = ", ".join(label_md(n) for n in found["table1_norms"])
    return prose("needed", norms=norms, n_meshes=len(found["N"]), parts="; ".join(parts))


def _fastest_brief(found: Mapping, labels: Mapping[str, str]) -> list[str]:
    if not found["fastest"]:
        return []
    first, *rest = found["fastest"]
    tied = [labels[r["config"]] for r in rest if r["vs_fastest"]["verdict"] == "tie"]
    open_ = [labels[r["config"]] for r in rest if r["vs_fastest"]["verdict"] == "undetermined"]
    if tied:
        verdict = prose("fastest_tied", configs=", ".join(tied))
    elif rest and not open_:
        verdict = prose("fastest_ahead")
    else:
        verdict = prose("fastest_untied") if rest else prose("fastest_alone")
    if open_:
        verdict += prose("fastest_open", configs=", ".join(open_))
    line = prose("fastest", N=found["N"][-1], name=_name(first, labels), time=fmt_timed(first), verdict=verdict)
    others = "; ".join(f"{_name(r, labels)} {fmt_timed(r)} {fmt_ratio(r['vs_fastest'])}" for r in rest)
    return [line + (" " + prose("fastest_others", others=others) if others else "")]


def _fair_brief(found: Mapping, labels: Mapping[str, str]) -> list[str]:
    lines = []
    for key, rows in found["fair"].items():
        if not rows:
            continue
        runs = "; ".join(
            f"N = {r['N']}: {_name(r['other'], labels)} {fmt_ratio(r['ratio'])} against {labels[r['ours']['config']]}"
            for r in rows
        )
        by: dict[str, list[str]] = {}
        for r in rows:
            by.setdefault(r["ratio"]["verdict"], []).append(str(r["N"]))
        verdict = "; ".join(f"{VERDICTS[v]} at N = {', '.join(Ns)}" for v, Ns in sorted(by.items()))
        comparison = prose(f"fair_{key}")
        lines.append(prose("fair", comparison=comparison, runs=runs, verdict=verdict[:1].upper() + verdict[1:]))
    return lines


def _cost_brief(exact: Mapping) -> list[str]:
    """The slopes of the exact solver's total errors against its total time, and per norm the cost of
    one more digit when the error falls (the slope and its whole interval below 0)."""
    names = dict(zip(COST_NORMS, ("L⁴", "W^{1,4}"), strict=True))
    if any(f"slope_{n}" not in exact for n in names):
        return []
    fits = " and ".join(f"{fmt_fit(exact[f'slope_{n}'])} in {name}" for n, name in names.items())
    clauses = []
    for n, name in names.items():
        s, f = exact[f"slope_{n}"], exact[f"time_factor_per_digit_{n}"]
        if s["value"] < 0 and (not s["interval"] or s["hi"] < 0):
            bounds = f" ({fmt_factor(f['lo'])}–{fmt_factor(f['hi'])})" if s["interval"] else ""
            clauses.append(prose("cost_digit", norm=name, factor=fmt_factor(f["value"]), bounds=bounds))
        else:
            clauses.append(prose("cost_flat", norm=name))
    return [prose("cost", label=exact["label"], fits=fits, clauses="; ".join(clauses))]


def _brief(found: Mapping, labels: Mapping[str, str]) -> list[str]:
    lines = [_needed_brief(found, labels), *_fastest_brief(found, labels), *_fair_brief(found, labels)]
    fits = [f"{labels[c]} p = {fmt_fit(p)}" for c, p in found["scaling"].items()]
    if fits:
        lines.append(prose("scaling", fits="; ".join(fits)))
    lines += _eoc_brief(found)
    if found["closest_l4"]:
        runs = "; ".join(
            f"1/{N}: {c['label']} {c['tol_label']} {100 * c['dev']:+.2f} % (exact {100 * c['exact_dev']:+.2f} %)"
            for N, c in sorted(found["closest_l4"].items())
        )
        lines.append(prose("closest", runs=runs))
    return lines + _cost_brief(found["exact"])


def _fair_table(found: Mapping, labels: Mapping[str, str]) -> list[str]:
    """Both comparisons side by side, one row per mesh."""
    fair = {k: {r["N"]: r for r in rows} for k, rows in found["fair"].items() if rows}
    if not fair:
        return []
    header = ["N"]
    for key in fair:  # same_warm_start, cold_against_cold
        header += [f"{key.replace('_', ' ')}: ours", "its time", "fastest other (tolerance)", "its time"]
        header.append("other / ours")

    def cells(r: Mapping | None) -> list[str]:
        if r is None:
            return ["—"] * 5
        ours, other = r["ours"], r["other"]
        return [labels[ours["config"]], fmt_timed(ours), _name(other, labels), fmt_timed(other), fmt_ratio(r["ratio"])]

    rows = [[str(N), *(c for by in fair.values() for c in cells(by.get(N)))] for N in found["N"]]
    return _table("fair_table", header, rows)


def _peer_table(found: Mapping) -> list[str]:
    if not found["peers"]:
        return []
    rows = [
        [v["label"], found["tolerance"].get(config) or "none", _counts(v["statuses"]), ", ".join(v["reasons"]) or "—"]
        for config, v in found["peers"].items()
    ]
    header = ["PETSc method", "selected tolerance", "statuses of all runs", "PETSc reasons"]
    version = ", ".join(v.removeprefix("PETSc ") for v in found["software"]["petsc"])
    return _table("peers", header, rows, "l", version=version)


def _table1_digits(found: Mapping) -> list[str]:
    n, last = len(found["N"]), found["N"][-1]

    def row(c: Mapping) -> list[str]:
        changed = f"{c['changed']}/{c['n_cells']}" + ("" if c["answered"] else " (partial)")
        statuses = " ".join(s if s != "inaccurate" else "inacc." for s in c["statuses"])
        keeping = f"{c['keeping']}/{n}" + (" selected" if c["selected"] else "")
        rel, time, alg = fmt_rel(c["worst_rel_change"]), fmt_timed(c["time_last"]), fmt_rel(c["alg_L4_rel_last"])
        return [c["label"], c["tol_label"], changed, rel, statuses, keeping, time, alg]

    header = ["solver", "tolerance", "cells changed", "worst rel. change", "status per N", "keeps digits"]
    header += [f"time N={last}", f"alg./disc. L⁴ N={last}"]
    numbers = {"n_norms": len(found["table1_norms"]), "n_meshes": n, "meshes": _meshes(found), "last": last}
    return _table("digits", header, [row(c) for c in found["cells"]], **numbers)


def _time_to_digits(found: Mapping, labels: Mapping[str, str]) -> list[str]:
    Ns, selected, scaling = list(found["N"]), found["selected"], found["scaling"]
    rows = []
    for config, tol in found["tolerance"].items():
        cells = [fmt_timed(selected[N][config]) if tol else "—" for N in Ns]
        rows.append([labels[config], tol or "none", *cells, fmt_fit(scaling[config]) if tol else "—"])
    return _table("time_to_digits", ["solver", "selected tolerance", *(f"N = {N}" for N in Ns), "p"], rows)


def _eoc_table(found: Mapping) -> list[str]:
    eocs, paper_rates = list(found["eoc"]), found["paper_l4_eoc"]
    if not eocs:
        return []

    def fixed(x: float) -> str:
        return f"{x:.4f}" if math.isfinite(x) else "—"

    rows = []
    if paper_rates and any(math.isfinite(r) for r in paper_rates):
        rows.append(["paper (Table 2)", "", *(f"{r:.4f}" for r in paper_rates), "", "", ""])
    for e in eocs:
        dev = [abs(x) for x in e.get("l4_dev_paper", []) if math.isfinite(x)]
        rates = [f"{r:.4f}" for r in e["eoc"]]
        l4 = f"{100 * max(dev):.2f} %" if dev else "—"
        rows.append([e["label"], e["tol_label"], *rates, fixed(e["max_dev_paper"]), fixed(e["max_dev_exact"]), l4])
    header = ["solver", "tolerance", *(h_label(N) for N in found["N"][1:]), "max Δ paper", "max Δ exact"]
    return _table("eoc_table", [*header, "L⁴ vs Table 1"], rows)


def _cost_table(found: Mapping) -> list[str]:
    exact = found["exact"]
    if not exact:
        return []
    errors = [exact.get(f"total_{n}", [math.nan] * len(exact["N"])) for n in COST_NORMS]
    columns = zip(exact["N"], exact["build_s"], exact["time"], exact["total_time"], *errors, strict=True)
    rows = [[h_label(N), fmt_time(b), fmt_timed(t), fmt_timed(s), *map(sci_md, e)] for N, b, t, s, *e in columns]
    header = ["h", "assembly", "solve", "total", *(label_md(n) for n in COST_NORMS)]
    return _table("cost_table", header, rows, label=exact["label"])


FAR = 0.1  # a residual at least this large (relative) is far from the KKT point, not near a tolerance


def _stops_table(found: Mapping) -> list[str]:
    """PETSc's stopping test against the certificate (``findings._stop_disagreements``); the runs
    PETSc called converged with a residual of at least ``FAR`` named in a sentence."""
    rows, far = [], [e for e in found["stop_disagreements"] if e["converged"] and e["lo"] >= FAR]
    for e in found["stop_disagreements"]:
        conv = (f"{e['converged']} ({', '.join(e['reasons'])}): {e['largest']} {fmt_rel(e['lo'])}–{fmt_rel(e['hi'])}"
                if e["converged"] else "—")
        acc = (f"{e['accepted']} ({', '.join(e['limits'])}): at most {fmt_rel(e['accepted_worst'])}"
               if e["accepted"] else "—")
        rows.append([e["label"], conv, acc])
    if not rows:
        return []
    items = "; ".join(f"{e['label']}, {e['converged']} runs ({', '.join(e['reasons'])}) with {e['largest']} "
                      f"{e['lo']:.2f}–{e['hi']:.2f}" for e in far)
    summary = prose("stops_far", items=items, far=FAR) if far else prose("stops_near", far=FAR)
    header = ["PETSc method", "converged, rejected: runs (reasons): largest residual", "stopped, accepted: runs"]
    return _table("stops", header, rows, "l", summary=summary)


def _failure_rows(bad: Sequence[Run]) -> list[list[str]]:
    """Failed, inaccurate and skipped runs grouped by (solver, status, reason)."""
    groups: dict[tuple[str, str, str], list[tuple[int, str]]] = {}
    worst: dict[tuple[str, str, str], float] = {}
    for r in bad:
        key = (r.label, r.status, r.reason or "—")
        groups.setdefault(key, []).append((r.N, r.tol_label))
        ratio = r.kkt_worst / r.kkt_required
        if r.status == "inaccurate" and math.isfinite(ratio):  # one row per solver, the worst ratio
            worst[key] = max(worst.get(key, 0.0), ratio)
    rows = []
    for key, runs in groups.items():
        label, status, reason = key
        tols = sorted(dict.fromkeys(t for _, t in runs), key=tolerance_key)
        if key in worst:
            where = "; ".join(f"{t} at {', '.join(str(N) for N, u in runs if u == t)}" for t in tols)
            reason = f"{reason} (up to ×{worst[key]:.1f})"
        else:
            where = f"{', '.join(tols)} at N = {', '.join(str(N) for N in dict.fromkeys(N for N, _ in runs))}"
        rows.append([label, status, where, reason])
    return rows


def _failures(runs: Sequence[Run]) -> list[str]:
    bad = [r for r in runs if r.status != "ok"]
    header = ["solver", "status", "tolerance at N", "reason"]
    return ["", prose("failures"), "", md_table(header, _failure_rows(bad), align="l") if bad else "None."]


def work_precision_md(
    runs: Sequence[Run], found: Mapping, source: str = "paper", protocol: Protocol | None = None
) -> str:
    """``work_precision.md`` from the runs of the measurement table (``work_precision.csv``) and
    ``findings.findings``; ``source``: the scene whose exact solutions were reused; ``protocol``:
    the timing protocol they were measured under (default: its defaults)."""
    labels = {r.config: r.label for r in runs}
    lines = [prose("header"), "", *_setup(runs, found, source, protocol or Protocol()), *_rules(runs, found)]
    lines += ["", prose("findings"), "", *_brief(found, labels)]
    lines += _table1_digits(found) + _time_to_digits(found, labels) + _fair_table(found, labels)
    lines += _peer_table(found) + _stops_table(found) + _eoc_table(found) + _cost_table(found) + _failures(runs)
    return re.sub(r"\n{3,}", "\n\n", "\n".join(lines)).rstrip() + "\n"


def report_stage(
    csv_path: str | os.PathLike,
    paper_table1: str | os.PathLike,
    paper_table2: str | os.PathLike,
    out_md: str | os.PathLike,
    source: str = "paper",
    timing: Mapping | None = None,
) -> dict:
    """Stage ``work_precision_report``: the findings (against the published Tables 1 and 2 in
    ``workflow/reference/``) rendered into ``work_precision.md``; ``timing``: the study's
    ``timing`` block (the protocol of its measurements)."""
    from signorini.formatting import markdown_text
    from signorini.pipeline.artifacts import atomic_write_text
    from signorini.studies.paper.reference import by_mesh, read_table_csv
    from signorini.studies.work_precision.table import read_runs

    runs = read_runs(csv_path)
    p1, p2 = read_table_csv(paper_table1), read_table_csv(paper_table2)
    protocol = Protocol.from_mapping(timing)
    found = findings(runs, TABLE1_NORMS, by_mesh(p1, "L4"), by_mesh(p2, "L4"), protocol)
    atomic_write_text(out_md, markdown_text(work_precision_md(runs, found, source, protocol)))
    return found
