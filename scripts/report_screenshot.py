"""Screenshot one result of the Snakemake report in headless Chromium.

``python scripts/report_screenshot.py results/report.html results/report/table1.html out.png
[1400,900]`` opens the result through the report's own ``app.setView`` once the page has loaded;
``python scripts/report_screenshot.py --click results/report.html out.png Paper Tables "table1.md page"``
clicks through the report as a reader does: each argument is the text of a menu entry (a category or
subcategory) to click, the last one the words of the result's row whose view button to click
(the screenshots in docs/evidence/report/).  A temporary copy of the report carries the script."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile

CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                  "--disable-component-update", "--disable-sync", "--no-first-run", "--virtual-time-budget=8000"]


CLICKS = """<script>
// click the menu entries by their text, then the view button of the row holding all given words;
// a step that finds nothing writes what it looked for into the page, so the screenshot shows it
function fail(what) {{ document.body.innerHTML = '<h1>not found: ' + what + '</h1>'; throw what; }}
function menu(text) {{
  const a = [...document.querySelectorAll('a')].find(a => a.textContent.trim() === text);
  a ? a.click() : fail('menu entry ' + text);
}}
function row(words) {{
  const tr = [...document.querySelectorAll('tr')].find(r => words.every(w => r.textContent.includes(w)));
  const a = tr && tr.querySelector('a');
  a ? a.click() : fail('row ' + words.join(' '));
}}
window.addEventListener('load', () => {{
  const steps = {steps};
  steps.forEach((step, k) => setTimeout(() => k < steps.length - 1 ? menu(step) : row(step.split(' ')), 600 * (k + 1)));
}});
</script>"""


def _shoot(html: str, js: str, png: str, size: str) -> None:
    end = html.rindex("</body>")
    with tempfile.NamedTemporaryFile("w", suffix=".html", delete=False, encoding="utf-8") as copy:
        copy.write(html[:end] + js + html[end:])
    try:
        subprocess.run(["chromium", *CHROMIUM_FLAGS, f"--user-data-dir={tempfile.mkdtemp()}",
                        f"--screenshot={png}", f"--window-size={size}", f"file://{copy.name}"],
                       check=True, capture_output=True, timeout=300)
    finally:
        os.unlink(copy.name)


def click_through(report: str, png: str, steps: list[str], size: str = "1400,900") -> None:
    """Click the menu entries ``steps[:-1]`` by their text, then the row with the words of ``steps[-1]``."""
    with open(report, encoding="utf-8") as f:
        _shoot(f.read(), CLICKS.format(steps=json.dumps(steps)), png, size)


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
    _shoot(html, js, png, size)


if __name__ == "__main__":
    if sys.argv[1] == "--click":
        click_through(sys.argv[2], sys.argv[3], sys.argv[4:])
    else:
        screenshot(*sys.argv[1:5])
