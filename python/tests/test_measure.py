"""Measurements from Python: `asnr.sfr`, `asnr.measure` and the metrics of `asnr.evaluate`.

The slanted edge is rendered here with numpy: the exact image of a Gaussian-blurred step
integrated over square pixels (as imaging/tests/sfr.rs renders it), whose MTF along the edge's
normal is exp(-2 pi^2 s^2 f^2) sinc(f cos t) sinc(f sin t). The command line these tests compare
with is `$ASNR_BIN` (see test_asnr.py).
"""

from __future__ import annotations

import json
import math
import os
import struct
import subprocess
import zlib
from pathlib import Path

import numpy as np
import pytest

import asnr

ROOT = Path(__file__).resolve().parents[2]
PAPER = ROOT / "examples" / "paper-theory.toml"
BIN = Path(os.environ.get("ASNR_BIN", ROOT / "target" / "debug" / "asnr"))
SIZE = 160


def cli_json(*args: str) -> dict:
    done = subprocess.run([str(BIN), *args], capture_output=True, check=False)
    assert done.returncode == 0, done.stderr.decode()
    return json.loads(done.stdout)


_erfc = np.vectorize(math.erfc)


def _h2(t: np.ndarray) -> np.ndarray:
    """The second antiderivative of the normal distribution function Phi: H'' = Phi."""
    phi = 0.5 * _erfc(-t / math.sqrt(2.0))
    density = np.exp(-t * t / 2.0) / math.sqrt(2.0 * math.pi)
    return (t * t + 1.0) / 2.0 * phi + t / 2.0 * density


def edge_image(theta_deg: float, sigma: float, dark: float, bright: float, size: int = SIZE) -> np.ndarray:
    """The exact mean over each pixel of Phi(n / sigma), n the distance from an edge through the
    frame's middle at theta_deg off vertical: sigma^2/(a c) times H's second difference over the
    pixel's corners."""
    c0 = (size - 1) / 2.0 + 0.3
    t = math.radians(theta_deg)
    a, c = math.cos(t), -math.sin(t)
    k = a * c0 + c * c0
    j, i = np.mgrid[0:size, 0:size].astype(np.float64)
    u = lambda x, y: (a * x + c * y - k) / sigma  # noqa: E731
    lo_x, hi_x, lo_y, hi_y = i - 0.5, i + 0.5, j - 0.5, j + 0.5
    fraction = sigma * sigma / (a * c) * (_h2(u(hi_x, hi_y)) - _h2(u(lo_x, hi_y)) - _h2(u(hi_x, lo_y)) + _h2(u(lo_x, lo_y)))
    return dark + (bright - dark) * fraction


def truth(f: np.ndarray, theta_deg: float, sigma: float) -> np.ndarray:
    t = math.radians(theta_deg)
    return np.exp(-2.0 * math.pi**2 * sigma**2 * f**2) * np.abs(np.sinc(f * math.cos(t)) * np.sinc(f * math.sin(t)))


def truth_mean(theta_deg: float, sigma: float) -> float:
    """The mean to Nyquist (0.5 cycles/pixel), trapezoidal rule on 20 000 intervals (error < 1e-9)."""
    f = np.linspace(0.0, 0.5, 20_001)
    m = truth(f, theta_deg, sigma)
    return float((m.sum() - 0.5 * (m[0] + m[-1])) * (f[1] - f[0]) / 0.5)


def write_png16(path: Path, levels: np.ndarray) -> Path:
    """A 16-bit grayscale PNG of whole grey levels (rows top to bottom)."""
    h, w = levels.shape
    codes = np.clip(np.rint(levels), 0, 65535).astype(">u2")
    raw = b"".join(b"\x00" + codes[r].tobytes() for r in range(h))

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", w, h, 16, 0, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))
    return path


# --- the slanted edge ----------------------------------------------------------------------


@pytest.mark.parametrize("angle", [2.0, 5.0, 10.0])
def test_an_exact_edge_gives_the_mtf_within_the_stated_accuracy(angle):
    sigma = 0.8
    result = asnr.sfr(edge_image(angle, sigma, 0.2, 1.0))
    expected = truth_mean(angle, sigma)
    # the stated accuracy without noise: the mean MTF to Nyquist within 0.2 %
    assert abs(result["mean_mtf"] / expected - 1.0) < 2e-3, (result["mean_mtf"], expected)
    assert abs(result["edge_angle_deg"] - angle) < 0.02
    f = np.asarray(result["frequency_cyc_per_px"])
    mtf = np.asarray(result["mtf"])
    to_nyquist = f <= 0.5 + 1e-12
    assert np.max(np.abs(mtf[to_nyquist] - truth(f[to_nyquist], angle, sigma))) < 5e-3
    assert abs(result["mtf_nyquist"] - truth(np.array(0.5), angle, sigma)) < 5e-3
    assert len(result["edges"]) == 1 and result["uncertainty"] == "esf-bins"


def test_sfr_equals_the_command_line_and_arrays_equal_files(tmp_path):
    levels = np.rint(edge_image(5.0, 0.8, 2000.0, 40000.0))
    path = write_png16(tmp_path / "edge.png", levels)
    ours = asnr.sfr(path, pixel_pitch_um=2.0)
    theirs = cli_json("sfr", str(path), "--json", "--pixel-pitch-um", "2")
    assert ours == theirs
    # the same grey levels as a uint16 array: the same numbers
    from_array = asnr.sfr(levels.astype(np.uint16), pixel_pitch_um=2.0)
    assert from_array["mean_mtf"] == ours["mean_mtf"] and from_array["mtf"] == ours["mtf"]
    # a ROI as a tuple or as the command line's text
    assert asnr.sfr(path, roi=(20, 10, 120, 140)) == asnr.sfr(path, roi="20,10,120,140")
    assert asnr.sfr(path, roi=(20, 10, 120, 140)) == cli_json("sfr", str(path), "--json", "--roi", "20,10,120,140")


def _stack(tmp_path: Path, n: int, seed: int) -> list[Path]:
    rng = np.random.default_rng(seed)
    image = edge_image(5.0, 0.8, 2000.0, 40000.0)
    return [write_png16(tmp_path / f"frame-{k}.png", rng.poisson(image).astype(np.float64)) for k in range(n)]


def test_measure_equals_the_command_line(tmp_path):
    frames = _stack(tmp_path, 4, 7)
    edge = write_png16(tmp_path / "edge.png", np.rint(edge_image(5.0, 0.8, 2000.0, 40000.0)))
    white, black = "120,20,24,24", "10,20,24,24"
    regions = ["--white", white, "--black", black]
    ours = asnr.measure(frames, white=white, black=black, edge=edge)
    theirs = cli_json("measure", *map(str, frames), *regions, "--edge", str(edge), "--json")
    assert ours == theirs
    measured = ours["measured_asnr"]
    assert measured["asnr"] == pytest.approx(ours["snr"] * measured["mean_mtf"], rel=1e-12)
    # beside the paper's scene, with its pixel aperture
    ours = asnr.measure(frames, white=(120, 20, 24, 24), black=(10, 20, 24, 24), edge=edge, compare=asnr.load(str(PAPER)))
    theirs = cli_json("measure", *map(str, frames), *regions, "--edge", str(edge), "--compare", str(PAPER), "--json")
    assert ours == theirs
    assert ours["compare"]["asnr_ratio"] == pytest.approx(measured["asnr"] / ours["compare"]["asnr"], rel=1e-12)
    # the stack as arrays: the same numbers
    arrays = np.stack([np.asarray(_read_png16(p), dtype=np.uint16) for p in frames])
    from_arrays = asnr.measure(arrays, white=white, black=black)
    assert from_arrays["snr"] == asnr.measure(frames, white=white, black=black)["snr"]


def _read_png16(path: Path) -> np.ndarray:
    """The grey levels of a PNG that write_png16 wrote."""
    data = path.read_bytes()
    w, h = struct.unpack(">II", data[16:24])
    idat_length = struct.unpack(">I", data[33:37])[0]
    raw = zlib.decompress(data[41 : 41 + idat_length])
    rows = [np.frombuffer(raw[r * (2 * w + 1) + 1 : (r + 1) * (2 * w + 1)], dtype=">u2") for r in range(h)]
    return np.array(rows, dtype=np.uint16)


# --- metrics -------------------------------------------------------------------------------


def test_metrics_equal_the_command_line_and_the_perfect_lens_closed_form():
    scene = asnr.load(str(PAPER))
    report = asnr.evaluate(scene, metrics=True, task="disk:20:0.05", frame_rate_hz=30)
    theirs = cli_json("evaluate", str(PAPER), "--json", "--metrics", "--task", "disk:20:0.05", "--frame-rate-hz", "30")
    assert report.to_dict() == theirs
    # Fellgett-Linfoot with MTF = 1 and a flat object of contrast c: C = 1/2 log2(1 + SNR0^2 c^2)
    for contrast in (1.0, 0.25):
        r = asnr.evaluate(scene, contrast=contrast)
        closed = 0.5 * math.log2(1.0 + r.snr0**2 * contrast**2)
        assert r.capacity_perfect_lens_bits_per_pixel == pytest.approx(closed, rel=1e-12)
        assert 0.0 < r.capacity_bits_per_pixel < closed
        assert r.neq_zero == pytest.approx(r.snr0**2, rel=1e-12)
    assert report.capacity_bits_per_pixel_per_second == pytest.approx(30 * report.capacity_bits_per_pixel, rel=1e-12)
    assert report.detectability is not None and report.ideal_lens is not None
    # without metrics: the plain report
    assert "capacity_bits_per_pixel" not in asnr.evaluate(scene).fields()


def test_bad_metrics_words_raise_naming_the_value():
    with pytest.raises(asnr.SceneError, match="power-law:BETA"):
        asnr.evaluate(asnr.load(), object="pink")
    with pytest.raises(asnr.SceneError, match="disk:DIAMETER_UM:CONTRAST"):
        asnr.evaluate(asnr.load(), task="square:2:1")


# --- bad input -----------------------------------------------------------------------------


def test_bad_input_raises_naming_the_reason(tmp_path):
    edge = edge_image(5.0, 0.8, 0.2, 1.0)
    with pytest.raises(ValueError, match=r"images\[0\] \(array\).*no edge"):
        asnr.sfr(np.full((SIZE, SIZE), 0.5) + 1e-3 * np.sin(np.arange(SIZE))[None, :])
    for angle, word in ((0.001, "0.00°"), (45.0, "45.00°")):
        with pytest.raises(ValueError, match=f"{word}.*ISO 12233"):
            asnr.sfr(edge_image(angle, 0.8, 0.2, 1.0))
    saturated = np.minimum(np.rint(edge_image(5.0, 0.8, 10000.0, 80000.0)), 65535).astype(np.uint16)
    with pytest.raises(ValueError, match="saturated"):
        asnr.sfr(saturated)
    with pytest.raises(ValueError, match="every frame of a stack must have the same size"):
        asnr.sfr([edge, edge[:100, :100]])
    with pytest.raises(ValueError, match="ROI.*outside"):
        asnr.sfr(edge, roi=(100, 0, 100, 50))
    with pytest.raises(ValueError, match=r"shape \(3, 4, 5, 6\)"):
        asnr.sfr(np.zeros((3, 4, 5, 6)))
    with pytest.raises(ValueError, match="int32.*expected uint8, uint16 or floating-point"):
        asnr.sfr(np.zeros((SIZE, SIZE), dtype=np.int32))
    nan = edge.copy()
    nan[3, 4] = np.nan
    with pytest.raises(ValueError, match="row 3, column 4: expected finite"):
        asnr.sfr(nan)
    # a 16-bit PNG whose header claims 10^6 x 10^6 pixels: refused from the header
    huge = tmp_path / "huge.png"
    huge.write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\x00\x0dIHDR" + struct.pack(">II", 10**6, 10**6) + bytes([16, 0, 0, 0, 0, 0, 0, 0, 0]))
    with pytest.raises(ValueError, match="huge.png.*1000000 × 1000000"):
        asnr.sfr(huge)
    with pytest.raises(ValueError, match="missing.png"):
        asnr.sfr(tmp_path / "missing.png")
    # the measured ASNR needs one edge, and one MTF
    stack = [edge, edge * 1.01]
    with pytest.raises(ValueError, match="one of edge and mtf_csv"):
        asnr.measure(stack, white="120,20,8,8", black="10,20,8,8", edge=edge, mtf_csv="m.csv")
    with pytest.raises(ValueError, match="white region `1,2,3`"):
        asnr.measure(stack, white="1,2,3", black="10,20,8,8")
    with pytest.raises(ValueError, match=r"1 frame\(s\); at least 2 are needed"):
        asnr.measure([edge], white="120,20,8,8", black="10,20,8,8")
