"""The paper's Fig. 2b from the Python API: the ASNR at F/2.5 against the spectral range.

"Theory": the paper's chromatic metalens (F/2.5, f0 = 3.36 mm, designed for 800 nm) with a
Gaussian spectrum centred at 800 nm, flat efficiency and QE (examples/paper-theory.toml, the
scene `asnr` embeds). "Simulated": the same with tabulated τ1(λ), T(λ) and QE(λ)
(examples/paper-simulated.toml: ILLUSTRATIVE tables shaped like the paper's, not its data).
The range is the Gaussian's 2√2σ, 2 to 200 nm in steps of 2 nm, as `cargo xtask figures` sweeps
it; the paper's four band-pass filters (10, 40, 52 and 125 nm FWHM) are marked.

    pip install "asnr-….whl[plot]"     # or, from the clone: pip install "./python[plot]"
    python examples/python/fig2b.py --out target/fig2b

writes fig2b.png, fig2b.svg and the curves as fig2b-theory.csv and fig2b-simulated.csv (the
bytes `asnr sweep --csv` writes for the same sweeps).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import asnr  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
#: the paper's band-pass filters, FWHM in nm (SI section 1b)
FILTERS_NM = (10.0, 40.0, 52.0, 125.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "target" / "fig2b", help="output folder")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)

    ranges = {"spectrum.range_nm": (2, 200, 100)}
    curves = {
        "theory": ("theory: flat τ1 and QE", asnr.load().with_({"lens.f_number": 2.5})),
        "simulated": (
            "simulated: tabulated τ1(λ), QE(λ) (illustrative)",
            asnr.load(ROOT / "examples" / "paper-simulated.toml"),
        ),
    }
    fig, ax = plt.subplots(figsize=(6.4, 4.2), dpi=150)
    top = 0.0
    for offset, (name, (label, scene)) in zip((8, -14), curves.items()):
        frame = asnr.sweep(scene, ranges)
        (args.out / f"fig2b-{name}.csv").write_text(asnr.to_csv(frame))
        # a DataFrame with pandas (the `plot` extra), a dict of arrays without: np.asarray reads both
        x, y = np.asarray(frame["spectrum.range_nm"]), np.asarray(frame["asnr"])
        (line,) = ax.plot(x, y, label=label, lw=1.8)
        best = y.argmax()
        ax.plot(x[best], y[best], "o", color=line.get_color(), ms=5)
        top = max(top, y[best])
        ax.annotate(
            f"best of the grid: {y[best]:.2f} at {x[best]:.0f} nm",
            (x[best], y[best]),
            textcoords="offset points",
            xytext=(8, offset),
            fontsize=8,
            color=line.get_color(),
            bbox={"fc": "white", "ec": "none", "alpha": 0.85, "pad": 1},
        )
        print(f"{name:>10}: best ASNR {y[best]:.4f} at a {x[best]:.0f} nm range")
    for i, width in enumerate(FILTERS_NM):
        ax.axvline(width, color="0.6", ls="--", lw=0.8, label="the paper's filters: 10, 40, 52, 125 nm (FWHM)" if i == 0 else None)
    ax.set_xlabel("spectral range 2√2σ (nm)")
    ax.set_ylabel("ASNR")
    ax.set_title("Fig. 2b — ASNR at F/2.5 against spectral range (Gaussian at 800 nm)", fontsize=10)
    ax.set_xlim(0, 200)
    ax.set_ylim(0, 1.12 * top)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    for suffix in ("png", "svg"):
        fig.savefig(args.out / f"fig2b.{suffix}")
    print(f"wrote {args.out / 'fig2b.png'} and .svg, and the curves as CSV")


if __name__ == "__main__":
    main()
