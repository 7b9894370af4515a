"""A camera series from the emva1288 package's camera model, and the check of `asnr characterize`
on it (run by `cargo xtask emva`, part of `cargo xtask ci`).

    python emva_series.py OUT_DIR --asnr PATH/TO/asnr

writes OUT_DIR/series.toml with a capped (dark) stack and 13 illuminated stacks of 16 frames each
(64 x 64 pixels, 12-bit values in 16-bit grayscale PNG), the illumination doubling from 1/1024
of the radiance that fills the full well up to twice it (the paper's SI camera characterization
halves the light at each step); runs `asnr characterize OUT_DIR/series.toml --json --plot
OUT_DIR/transfer.svg`; and checks what it finds against the camera's own parameters:

- conversion gain K = 0.5 DN/e- (the model multiplies electrons by K), within 2 %;
- read noise sqrt(sigma2_dark_0) = 6 e- (the model's dark variance, 36 e-^2; `asnr characterize`
  subtracts the quantization noise of 1/12 DN^2 from the dark variance, as EMVA 1288 does),
  within 3 %;
- STF slope with the capped black subtracted 1 (the model is linear below its full well),
  within 0.01;
- PTC slope with the capped black subtracted 0.5 (Poisson shot noise), within 0.01;
- the saturation point (the largest variance) at the level that reaches the full well
  (u_esat = 6000 e-), or the one below it.

The tolerances: with 16 frames and 4096 pixels the mean per-pixel sample variance has a
relative standard error of sqrt(2/15)/64 = 0.57 %, so K (a slope of variances) is good to about
0.3 %, and the read noise (the square root of one variance) to 0.3 %; the stated tolerances are
several times that. The generator is seeded, so the series is the same on every run.
"""

import argparse
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
from PIL import Image
from emva1288.camera import Camera

SEED = 1288
WIDTH = HEIGHT = 64
FRAMES = 16
K = 0.5  # DN/e-; on the model's grid of gains linspace(0.1, 2.6, 26)
SIGMA2_DARK = 36.0  # e-^2: 6 e- read noise
DARK_SIGNAL = 50.0  # e-: the electronic offset, far enough above 0 that the model's clip at 0 e- never acts
FULL_WELL = 6000.0  # e-
BLACK_OFFSET = 20.0  # DN; on the model's grid linspace(0, 255, 256)
FRACTIONS = [2.0 ** k for k in range(-10, 1)] + [1.4, 2.0]  # of the radiance filling the full well


def camera():
    cam = Camera(
        bit_depth=12,
        width=WIDTH,
        height=HEIGHT,
        K=K,
        K_min=0.1,
        K_max=2.6,
        K_steps=26,
        blackoffset=BLACK_OFFSET,
        blackoffset_min=0,
        blackoffset_max=255,
        blackoffset_steps=256,
        dark_current_ref=0.0,  # no dark current: the dark noise is the read noise alone
        dark_signal_0=DARK_SIGNAL,
        sigma2_dark_0=SIGMA2_DARK,
        u_esat=FULL_WELL,
        seed=SEED,
    )
    assert abs(cam.K - K) < 1e-12, cam.K
    assert abs(cam.blackoffset - BLACK_OFFSET) < 1e-12, cam.blackoffset
    return cam


def write_stack(cam, radiance, folder):
    folder.mkdir(parents=True, exist_ok=True)
    for i in range(FRAMES):
        frame = cam.grab(radiance).astype(np.uint16)
        Image.fromarray(frame).save(folder / f"frame-{i:02d}.png")


def generate(out):
    cam = camera()
    # the radiance whose mean signal fills the full well (the model's own inverse)
    full = float(np.mean(cam.get_radiance_for(mean=K * FULL_WELL)))
    lines = ['# written by imaging/tests/emva/emva_series.py (emva1288 camera model)', 'region = "0,0,64,64"', ""]
    write_stack(cam, 0.0, out / "dark")
    lines += ["[dark]", 'frames = ["dark"]', ""]
    for i, f in enumerate(FRACTIONS):
        write_stack(cam, full * f, out / f"level-{i:02d}")
        lines += ["[[levels]]", f"illumination = {full * f!r}", f'frames = ["level-{i:02d}"]', ""]
    (out / "series.toml").write_text("\n".join(lines))


def check(result):
    failures = []

    def within(name, got, want, tol, relative):
        error = abs(got / want - 1) if relative else abs(got - want)
        ok = error <= tol
        print(f"  {name:<28} {got:.5f}  expected {want:.5f} {'±' if not relative else 'within'} "
              f"{tol * 100 if relative else tol:g}{' %' if relative else ''}  {'ok' if ok else 'FAIL'}")
        if not ok:
            failures.append(name)

    read = math.sqrt(SIGMA2_DARK)
    within("conversion gain K (DN/e-)", result["conversion_gain"], K, 0.02, True)
    within("read noise (e-)", result["read_noise_e"], read, 0.03, True)
    within("STF slope (subtracted)", result["stf"]["slope"], 1.0, 0.01, False)
    within("PTC slope (subtracted)", result["ptc"]["slope"], 0.5, 0.01, False)
    print(f"  STF slope, raw               {result['stf_raw']['slope']:.5f}  (not checked: the offset bends it)")
    print(f"  PTC slope, raw               {result['ptc_raw']['slope']:.5f}  (not checked: the offset and the read noise bend it)")
    full = FRACTIONS.index(1.0)
    saturation = result["saturation"]
    ok = saturation in (full - 1, full)
    print(f"  saturation level             {saturation}  expected {full - 1} or {full} (the full well)  "
          f"{'ok' if ok else 'FAIL'}")
    if not ok:
        failures.append("saturation")
    return failures


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--asnr", required=True)
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    generate(args.out)
    command = [args.asnr, "characterize", str(args.out / "series.toml"), "--json",
               "--plot", str(args.out / "transfer.svg")]
    print("$ " + " ".join(command))
    run = subprocess.run(command, capture_output=True, text=True)
    if run.returncode != 0:
        print(run.stderr, file=sys.stderr)
        return 1
    result = json.loads(run.stdout)
    failures = check(result)
    if failures:
        print("emva1288 cross-check FAILED: " + ", ".join(failures), file=sys.stderr)
        return 1
    print("emva1288 cross-check passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
