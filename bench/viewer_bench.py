"""The map viewer in a headless browser: how soon a big map is drawn, how soon a proof shows (a benchmark).

Starts ``bootmap serve`` (or uses --url), posts a 2,000-step exploration of a random 5x6 grid world (104
dstates, 30 places; ``support.gridworld``, seed 4), then in Debian's chromium (Playwright,
``--no-sandbox``):

1. opens the page on it ``--repeats`` times, each in a fresh tab: the time from the page's request to
   the map drawn (the page sets ``data-drawn`` on its body and records ``performance.now()``, which
   counts from the navigation's start);
2. clicks two dstates on the map, ``--repeats`` pairs: the time from the second click to the proof on the
   page (the page records it; the solver re-solves the tableau for each question).

Targets: the map in under 1 s, the proof in under 1.5 s (medians). Exit status 1 if one is missed.

    .venv/bin/python bench/viewer_bench.py [--repeats 5] [--url URL]
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

import httpx
import numpy as np
from playwright.sync_api import sync_playwright

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # tests/support: grid worlds, the checker
from support.gridworld import random_world, walk
from service_bench import start_server
from targets import Targets

MAP_MAX_S = 1.0
WHY_MAX_S = 1.5


def tableau() -> dict:
    rng = np.random.default_rng(4)
    world = random_world(rng, 5, 6, extra_edges=6, landmarks=0.3)
    return walk(world, 2000, rng, policy="explore").to_dict()


def measure(url: str, tableau_id: int, repeats: int, chromium: str) -> tuple[list[float], list[float], list[float]]:
    """Seconds: page request -> map drawn (in the page's clock, and the wall clock around goto), and
    second click -> proof shown, one figure per repeat."""
    in_page, wall, why = [], [], []
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=chromium, args=["--no-sandbox"], headless=True)
        for i in range(repeats + 1):  # the first is a warm-up (the browser's own start-up caches)
            context = browser.new_context(viewport={"width": 1280, "height": 1000})
            page = context.new_page()
            t0 = time.perf_counter()
            page.goto(f"{url}/?tableau={tableau_id}", wait_until="commit")
            page.wait_for_selector("body[data-drawn]", state="attached", timeout=60_000)
            took = time.perf_counter() - t0
            drawn = page.evaluate("window.bootmapTimes.drawn") / 1000
            names = page.locator("#map .dstate").evaluate_all("ns => ns.map(n => n.dataset.dstate)")
            page.locator(f'#map .dstate[data-dstate="{names[0]}"] circle').click(force=True)
            page.locator(f'#map .dstate[data-dstate="{names[1 + i]}"] circle').click(force=True)
            page.wait_for_function("() => ['different', 'same', 'undecided', 'failed'].includes(document.body.dataset.why)",
                                   timeout=60_000)
            verdict = page.evaluate("document.body.dataset.why")
            if verdict == "failed":
                raise SystemExit(f"why {names[0]} / {names[1 + i]} failed: {page.locator('#status').inner_text()}")
            if i > 0:
                in_page.append(drawn)
                wall.append(took)
                why.append(page.evaluate("window.bootmapTimes.why") / 1000)
            print(f"  {'warm-up' if i == 0 else f'run {i}'}: map drawn {drawn:.3f} s after the request "
                  f"(wall {took:.3f} s); {names[0]} / {names[1 + i]}: {verdict}, proof shown in "
                  f"{page.evaluate('window.bootmapTimes.why') / 1000:.3f} s", flush=True)
            context.close()
        browser.close()
    return in_page, wall, why


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--url", help="a running server (default: start one)")
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        raise SystemExit("chromium not installed: apt-get install chromium")
    doc = tableau()
    proc = None
    with tempfile.TemporaryDirectory() as tmp:
        url = args.url
        if url is None:
            proc, url = start_server(Path(tmp))
        try:
            with httpx.Client(base_url=url, timeout=120) as c:
                t0 = time.perf_counter()
                r = c.post("/tableaux", json=doc)
                r.raise_for_status()
                posted = time.perf_counter() - t0
                s = r.json()["map"]["summary"]
                layout = c.get(f"/tableaux/{r.json()['id']}/layout").json()["layout"]
            print(f"viewer bench: {len(doc['steps'])} steps -> {s['dstates']} dstates, {s['places']} places, "
                  f"{s['paths']} paths (posted and solved in {posted:.2f} s; layout {layout['method']}); "
                  f"{os.cpu_count()} CPUs, load {os.getloadavg()[0]:.2f}")
            in_page, wall, why = measure(url, r.json()["id"], args.repeats, chromium)
        finally:
            if proc is not None:
                proc.terminate()
                proc.wait(20)
    med = statistics.median
    print(f"\nmedians of {args.repeats}: map drawn {med(in_page):.3f} s after the request (wall {med(wall):.3f} s), "
          f"proof shown {med(why):.3f} s after the click; load now {os.getloadavg()[0]:.2f}\n")
    targets = Targets()
    targets.check("map of 2,000 steps drawn", med(in_page), "<", MAP_MAX_S, fmt="{:.3f}", unit=" s")
    targets.check("proof shown after two clicks", med(why), "<", WHY_MAX_S, fmt="{:.3f}", unit=" s")
    return targets.exit_status()


if __name__ == "__main__":
    sys.exit(main())
