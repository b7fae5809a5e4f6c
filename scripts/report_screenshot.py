"""Screenshot one result of the Snakemake report in headless Chromium, as a click in its menu
shows it: ``python scripts/report_screenshot.py results/report.html results/report/table1.html
out.png [1400,900]`` (the screenshots in docs/evidence/report/).  A temporary copy of the report
opens the result through the report's own ``app.setView`` once the page has loaded."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile

CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                  "--disable-component-update", "--disable-sync", "--no-first-run", "--virtual-time-budget=8000"]


def screenshot(report: str, result: str, png: str, size: str = "1400,900") -> None:
    with open(report, encoding="utf-8") as f:
        html = f.read()
    js = f"""<script>
window.addEventListener('load', () => setTimeout(() => {{
  const path = {json.dumps(result)};
  const kind = results[path].mime_type === 'text/html' ? 'html' : 'img';
  app.setView({{navbarMode: 'resultinfo', resultPath: path, content: kind, contentPath: results[path].data_uri}});
}}, 500));
</script>"""
    end = html.rindex("</body>")
    with tempfile.NamedTemporaryFile("w", suffix=".html", delete=False, encoding="utf-8") as copy:
        copy.write(html[:end] + js + html[end:])
    try:
        subprocess.run(["chromium", *CHROMIUM_FLAGS, f"--user-data-dir={tempfile.mkdtemp()}",
                        f"--screenshot={png}", f"--window-size={size}", f"file://{copy.name}"],
                       check=True, capture_output=True, timeout=300)
    finally:
        os.unlink(copy.name)


if __name__ == "__main__":
    screenshot(*sys.argv[1:5])
