"""The design page's speed, measured in a real browser (docs/app.md, "How fast").

Starts ``boringbar app`` on a free port, opens the page in Debian's headless Chromium
with Playwright and times, from the browser's side (each clock starts before the
action and stops when the view's status line names the new change):

- first load: from starting the command to the single-run view drawn;
- a gap change: the single-run view and the RMS response of 11 ratios redrawn;
- the analytic lobes redrawn after a change of the spindle speed (each bar's depth at
  it; the curves are kept), of the TMD's mass (the TMD bar's curve anew) and of the
  cavity's position (the ball bar's host anew, and the response);
- the ball bar's simulated lobes (the converged verdict at each speed), once.

Prints each figure with its target; ``--repeat N`` changes each control N times
(median and worst shown). ``--screenshots DIR`` then also saves the page's three tabs
as DIR/app_design.png, app_lobes.png (after simulating the ball bar's lobes) and
app_search.png (after a design search), the screenshots of docs/app.md.

    .venv/bin/python benchmarks/bench_app.py --repeat 5
    .venv/bin/python benchmarks/bench_app.py --repeat 1 --screenshots docs/img
"""

from __future__ import annotations

import argparse
import shutil
import socket
import statistics
import subprocess
import sys
import time
from pathlib import Path

from playwright.sync_api import sync_playwright

ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking",
        "--disable-component-update", "--disable-sync"]
#: the pause before each timed change (ms)
SETTLE_MS = 1000
TARGETS = {"first load": 5.0, "single run": 0.5, "response (11 ratios)": 3.0,
           "analytic lobes (speed)": 0.5, "analytic lobes (TMD mass)": 0.5,
           "analytic lobes (cavity)": 0.5, "simulated lobes (ball)": 5.0}


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


#: True once the status line of class ``cls`` (the host of a Panel pane, whose text is in
#: its shadow root) holds ``text``; the host is found once through every shadow root
STATUS_JS = """([cls, text]) => {
  const cache = window.__statusHosts || (window.__statusHosts = {});
  const find = (root) => {
    for (const el of root.querySelectorAll('*')) {
      if (el.classList && el.classList.contains(cls)) return el;
      const inner = el.shadowRoot && find(el.shadowRoot);
      if (inner) return inner;
    }
    return null;
  };
  let host = cache[cls];
  if (!host || !host.isConnected) host = cache[cls] = find(document);
  return !!host && (host.shadowRoot || host).textContent.includes(text);
}"""
#: how often (ms) the browser looks at a status line (Playwright's wait_for_selector
#: backs off to every 500 ms after 270 ms, too coarse for the redraws timed here)
POLL_MS = 5


def wait_drawn(page, view: str, change: int, timeout_s: float = 60) -> float:
    page.wait_for_function(STATUS_JS, arg=[f"status-{view}", f"change {change}: drawn in"],
                           polling=POLL_MS, timeout=timeout_s * 1000)
    return time.perf_counter()


def change(page, control: str, value: str) -> float:
    """Type ``value`` into a control and press Enter on a page at rest (the last
    redraw's painting done: each change is timed on its own); returns the clock."""
    page.wait_for_timeout(SETTLE_MS)
    box = page.locator(f".ctl-{control} input")
    box.fill(value)
    t0 = time.perf_counter()
    box.press("Enter")
    return t0


def screenshots(page, out: Path) -> None:
    """The page's three tabs, each after its work is done."""
    page.get_by_text("Design", exact=True).click()
    page.wait_for_selector(".status-run >> text=drawn in")
    page.wait_for_timeout(1500)  # the canvases paint after their data arrive
    page.screenshot(path=out / "app_design.png", full_page=True)
    page.get_by_text("Response and lobes").click()  # simulated by main() already
    page.wait_for_timeout(1500)
    page.screenshot(path=out / "app_lobes.png", full_page=True)
    page.get_by_text("Design search", exact=True).click()
    page.get_by_text("Start search").click()
    page.wait_for_selector(".search-status >> text=trials)", timeout=600_000)
    page.wait_for_timeout(1500)
    page.screenshot(path=out / "app_search.png", full_page=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--screenshots", metavar="DIR")
    args = ap.parse_args()
    port = free_port()
    t_start = time.perf_counter()
    server = subprocess.Popen([sys.executable, "-m", "boringbar", "app", "--port", str(port)],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    times: dict[str, list[float]] = {k: [] for k in TARGETS}
    try:
        url = f"http://127.0.0.1:{port}/"
        while True:
            try:
                socket.create_connection(("127.0.0.1", port), timeout=1).close()
                break
            except OSError:
                time.sleep(0.05)
        t_http = time.perf_counter()
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=shutil.which("chromium"), args=ARGS)
            page = browser.new_page(viewport={"width": 1500, "height": 1000})
            page.goto(url)
            times["first load"].append(wait_drawn(page, "run", 0) - t_start)
            wait_drawn(page, "bar", 0)
            print(f"server answering after {t_http - t_start:.2f} s; the first tab's views "
                  f"drawn after {time.perf_counter() - t_start:.2f} s")
            n = 0
            for i in range(args.repeat):  # the single run, on the first tab
                n += 1
                t0 = change(page, "ball-gap_mm", f"{0.20 + 0.01 * i:.2f}")
                times["single run"].append(wait_drawn(page, "run", n) - t0)
                wait_drawn(page, "bar", n)
            page.get_by_text("Response and lobes").click()  # a tab draws when shown
            wait_drawn(page, "lobes", n)
            for i in range(args.repeat):  # the response and the lobes, on the second
                n += 1
                t0 = change(page, "ball-gap_mm", f"{0.40 + 0.01 * i:.2f}")
                times["response (11 ratios)"].append(wait_drawn(page, "response", n) - t0)
                wait_drawn(page, "lobes", n)
                n += 1
                t0 = change(page, "rpm", f"{1000 + 50 * i:g}")
                times["analytic lobes (speed)"].append(wait_drawn(page, "lobes", n) - t0)
                wait_drawn(page, "response", n)
                n += 1  # the TMD's curve is drawn anew, the others are kept
                t0 = change(page, "tmd-mass_kg", f"{0.30 + 0.01 * i:.2f}")
                times["analytic lobes (TMD mass)"].append(wait_drawn(page, "lobes", n) - t0)
                wait_drawn(page, "response", n)
                n += 1  # every curve anew
                t0 = change(page, "cavity-position_mm", f"{125.0 - i:g}")
                times["analytic lobes (cavity)"].append(wait_drawn(page, "lobes", n) - t0)
                wait_drawn(page, "response", n)
            # the converged verdict at every speed of the ball bar (once: a minute or so)
            page.wait_for_timeout(SETTLE_MS)
            t0 = time.perf_counter()
            page.get_by_text("Simulate the ball bar's lobes").click()
            page.wait_for_function(STATUS_JS, arg=["status-simulated", "simulated cuts in"],
                                   polling=POLL_MS, timeout=600_000)
            times["simulated lobes (ball)"].append(time.perf_counter() - t0)
            if args.screenshots:
                screenshots(page, Path(args.screenshots))
            browser.close()
    finally:
        server.terminate()
        server.wait(timeout=10)
    for what, ts in times.items():
        print(f"{what:27s} median {statistics.median(ts):6.2f} s  worst {max(ts):6.2f} s  "
              f"(target {TARGETS[what]:g} s, {len(ts)} times)")


if __name__ == "__main__":
    main()
