#!/usr/bin/env python3
"""Opens fresh recordings in Rerun's own viewer and checks what it shows.

usage: viewer_screenshots.py [--out DIR] [--tmrotor BIN] [--rerun BIN]

What it does, in this order:

1. Writes a sweep of the built-in dual rotor (480–520 rad/s, 36 points) and a short
   transient run with the tmrotor binary (default target/release/tmrotor), and converts
   both with the package's exporter (`tmrotor.rerun.export`).
2. Starts a virtual X display (`Xvfb`) and opens each `.rrd` in Rerun's native viewer
   (the `rerun` command of the installed rerun-sdk, 0.41) with
   `--screenshot-to FILE --window-size 1600x1000`: the viewer lays out the file's own
   blueprint, renders it (on a CPU through Mesa's lavapipe Vulkan driver where there is no
   GPU) and saves what it drew. The PNGs land in DIR (default target/viewer-screenshots).
3. Asserts on the sweep's screenshot:
   * it is not blank (thousands of distinct colours);
   * the series are told apart by colour: at least five of the exporter's palette colours
     are drawn;
   * the plots show the whole ω range, not a window about the cursor: in the first
     amplitude plot (the top left of the blueprint's layout at this window size) the
     palette's points fill at least 100 distinct pixel columns (measured: 196 with the
     blueprint's x range, 21 without it, when the viewer shows 1 rad/s about its cursor);
   and on the transient's: not blank, at least three palette colours.

Exit status: 0 when the checks pass or when the viewer cannot run here (no Xvfb, no
rerun-sdk, no Vulkan driver, or the viewer exits without a screenshot), which is printed
as `viewer screenshots: skipped: <reason>`; 1 when a screenshot was taken and a check
fails; 2 for usage errors.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
WINDOW = "1600x1000"


def skip(reason: str) -> int:
    print(f"viewer screenshots: skipped: {reason}")
    return 0


def palette() -> list[tuple[int, int, int]]:
    """The exporter's first colours (the installed package's, as the export)."""
    from tmrotor.rerun import palette_colour

    return [palette_colour(j) for j in range(8)]


def pixels(png: Path):
    import numpy as np
    from PIL import Image

    return np.asarray(Image.open(png).convert("RGB")).astype(int)


def colour_mask(img, colour, tol: int = 14):
    import numpy as np

    return np.all(np.abs(img - np.array(colour)) <= tol, axis=2)


#: The first amplitude plot of the sweep's blueprint at WINDOW, as fractions of the
#: screenshot's width and height (x0, x1, y0, y1).
FIRST_PLOT = (0.131, 0.469, 0.06, 0.26)


def check(png: Path, min_colours: int, min_columns: int | None) -> list[str]:
    """Problems with a screenshot (empty when it passes)."""
    import numpy as np

    img = pixels(png)
    problems = []
    distinct = len(np.unique(img.reshape(-1, 3), axis=0))
    if distinct < 300:
        problems.append(f"{png.name}: only {distinct} distinct colours: a blank or unrendered view")
    h, w = img.shape[:2]
    x0, x1, y0, y1 = FIRST_PLOT
    plot = img[int(y0 * h) : int(y1 * h), int(x0 * w) : int(x1 * w)]
    drawn = []
    columns = np.zeros(plot.shape[1], dtype=bool)
    for c in palette():
        if colour_mask(img, c).sum() >= 40:
            drawn.append(c)
        columns |= colour_mask(plot, c).any(axis=0)
    if len(drawn) < min_colours:
        problems.append(
            f"{png.name}: {len(drawn)} of the exporter's palette colours drawn, "
            f"{min_colours} expected (series not told apart by colour)"
        )
    if min_columns is not None and columns.sum() < min_columns:
        problems.append(
            f"{png.name}: the palette's points fill {int(columns.sum())} pixel columns, "
            f"{min_columns} expected: the plots show a window of ω, not the whole range"
        )
    print(
        f"  {png.name}: {img.shape[1]}x{img.shape[0]} px, {distinct} colours, "
        f"{len(drawn)} palette colours drawn, points in {int(columns.sum())} pixel columns "
        "of the first plot"
    )
    return problems


def screenshot(rerun: str, rrd: Path, png: Path, env: dict) -> bool:
    png.unlink(missing_ok=True)
    try:
        subprocess.run(
            [rerun, str(rrd), "--screenshot-to", str(png), "--window-size", WINDOW],
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            timeout=240,
            check=False,
        )
    except subprocess.TimeoutExpired:
        return False
    return png.is_file() and png.stat().st_size > 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=ROOT / "target" / "viewer-screenshots")
    ap.add_argument("--tmrotor", type=Path, default=ROOT / "target" / "release" / "tmrotor")
    ap.add_argument("--rerun", default=None, help="the rerun command (default: rerun-sdk's)")
    args = ap.parse_args(argv)

    rerun = args.rerun or shutil.which("rerun") or str(Path(sys.executable).parent / "rerun")
    if not Path(rerun).exists() and not shutil.which(rerun):
        return skip("no rerun command (pip install 'tmrotor[rerun]')")
    xvfb = shutil.which("Xvfb")
    if xvfb is None:
        return skip("no Xvfb (Debian: apt-get install xvfb mesa-vulkan-drivers)")
    if not os.access(args.tmrotor, os.X_OK):
        return skip(f"no tmrotor binary at {args.tmrotor}")
    try:
        import numpy  # noqa: F401
        from PIL import Image  # noqa: F401
        from tmrotor.rerun import export
    except ImportError as e:
        return skip(f"the Python package or its image readers are missing ({e})")

    args.out.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix="tmrotor-viewer-"))
    sweep, transient = work / "sweep.mcap", work / "transient.mcap"
    for cmd in (
        [str(args.tmrotor), "sweep", "--omega", "480:520", "--no-verify", "-q", "-o", str(sweep)],
        [str(args.tmrotor), "transient", "--speed", "400", "--duration", "0.3", "-q",
         "-o", str(transient)],
    ):
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=600, check=False)
        if p.returncode != 0:
            print(p.stdout + p.stderr, file=sys.stderr)
            print(f"viewer screenshots: {' '.join(cmd)} failed", file=sys.stderr)
            return 1
    rrds = {name: export(mcap, work / f"{name}.rrd") for name, mcap in
            (("sweep", sweep), ("transient", transient))}

    display = ":93"
    server = subprocess.Popen(
        [xvfb, display, "-screen", "0", "1920x1200x24"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    checks = {"sweep": (5, 100), "transient": (3, None)}
    problems: list[str] = []
    try:
        time.sleep(2)
        if server.poll() is not None:
            return skip("Xvfb did not start")
        env = dict(os.environ, DISPLAY=display, XDG_RUNTIME_DIR=str(work))
        for name, rrd in rrds.items():
            png = args.out / f"rerun_{name}.png"
            # a second screenshot where the first fails a check (the viewer decides when
            # it has drawn; on a loaded machine it may have drawn less)
            for attempt in (1, 2):
                if not screenshot(rerun, rrd, png, env):
                    return skip(
                        f"Rerun's viewer saved no screenshot of {rrd.name} (no Vulkan or GL "
                        "driver it can use? Debian: apt-get install mesa-vulkan-drivers)"
                    )
                found = check(png, *checks[name])
                if not found:
                    break
                if attempt == 2:
                    problems += found
    finally:
        server.terminate()
        server.wait(timeout=10)

    for p in problems:
        print(f"viewer screenshots: FAIL: {p}", file=sys.stderr)
    if problems:
        return 1
    print(f"viewer screenshots: OK (Rerun's viewer; screenshots in {args.out})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
