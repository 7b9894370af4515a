"""evaluate_many over the 40 × 100 map against `asnr sweep --csv`, side by side.

    pip install ./python            # a release build of the extension
    cargo build --release -p asnr   # the release binary
    python python/bench/map.py --asnr target/release/asnr

Times the whole map (F/1.4–5 × 2–300 nm, 4000 points of the paper scene) on 2 threads: the
command as a whole process (`asnr sweep … --csv --threads 2`, wall clock) and, in this Python
process, `asnr.evaluate_many` on the same points (`threads=2`) plus `asnr.to_csv`; medians of
`--runs` runs, alternating. Checks that the CSVs are the same bytes.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import time

import asnr

ARGS = ["sweep", "--over", "lens.f_number=1.4:5:40", "--over", "spectrum.range_nm=2:300:100", "--csv", "--threads", "2"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--asnr", default="target/release/asnr", help="the asnr binary")
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--json", action="store_true", help="print one JSON object (for cargo xtask accuracy)")
    args = parser.parse_args()
    points = asnr.grid({"lens.f_number": (1.4, 5, 40), "spectrum.range_nm": (2, 300, 100)})
    scene = asnr.load()
    cli_times, py_times = [], []
    for _ in range(args.runs):
        start = time.perf_counter()
        theirs = subprocess.run([args.asnr, *ARGS], capture_output=True, check=True).stdout
        cli_times.append(time.perf_counter() - start)
        start = time.perf_counter()
        ours = asnr.to_csv(asnr.evaluate_many(scene, points, threads=2)).encode()
        py_times.append(time.perf_counter() - start)
        assert ours == theirs, "the CSVs differ"
    cli, py = statistics.median(cli_times), statistics.median(py_times)
    if args.json:
        print(json.dumps({"cli_s": cli, "python_s": py, "runs": args.runs, "identical": True}))
        return
    print(f"asnr sweep (whole process): {cli:.3f} s   evaluate_many + to_csv: {py:.3f} s   ratio {py / cli:.3f}   (medians of {args.runs}; CSVs identical)")


if __name__ == "__main__":
    main()
