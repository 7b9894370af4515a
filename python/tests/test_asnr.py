"""The Python package against the command line: the same scene gives the same numbers.

The `asnr` binary these tests compare with is `$ASNR_BIN`, or the debug build
(`target/debug/asnr`, which `cargo xtask python` builds first). Run with
`cargo xtask python` (part of `cargo xtask ci`), or after `pip install ./python` with
`ASNR_BIN=target/release/asnr pytest python/tests`.
"""

from __future__ import annotations

import _thread
import dataclasses
import json
import os
import pickle
import subprocess
import sys
import threading
import warnings
from pathlib import Path

import numpy as np
import pytest

import asnr

ROOT = Path(__file__).resolve().parents[2]
PAPER = ROOT / "examples" / "paper-theory.toml"
BIN = Path(os.environ.get("ASNR_BIN", ROOT / "target" / "debug" / "asnr"))


def cli(*args: str) -> bytes:
    """The `asnr` command's stdout (it must succeed)."""
    done = subprocess.run([str(BIN), *args], capture_output=True, check=False)
    assert done.returncode == 0, done.stderr.decode()
    return done.stdout


# --- scenes -------------------------------------------------------------------------------


def test_a_scene_loads_from_a_path_text_a_dict_or_the_embedded_default():
    embedded = asnr.evaluate(asnr.load()).asnr
    assert asnr.evaluate(asnr.load(PAPER)).asnr == embedded
    assert asnr.evaluate(asnr.load(str(PAPER))).asnr == embedded
    assert asnr.evaluate(asnr.load(PAPER.read_text())).asnr == embedded
    import tomllib

    as_dict = tomllib.loads(PAPER.read_text())
    assert asnr.evaluate(asnr.load(as_dict)).asnr == embedded
    assert "lens.f_number=2.8" in asnr.load().with_({"lens.f_number": 2.8}).overrides
    assert "[lens]" in asnr.load().to_toml()


def test_with_sets_keys_as_the_command_line_does():
    scene = asnr.load(PAPER)
    for f_number in (2.8, 4, np.float64(1.7), np.int64(3)):
        ours = asnr.evaluate(scene.with_({"lens.f_number": f_number})).to_dict()
        theirs = json.loads(cli("evaluate", str(PAPER), "--json", "--set", f"lens.f_number={f_number}"))
        assert ours == theirs
    shape = asnr.evaluate(scene.with_({"spectrum.shape": "tophat"})).asnr
    assert shape != asnr.evaluate(scene).asnr


def test_evaluate_is_the_json_report_of_the_command_line():
    report = asnr.evaluate(asnr.load(PAPER))
    theirs = json.loads(cli("evaluate", str(PAPER), "--json"))
    assert report.to_dict() == theirs
    assert report.asnr == theirs["asnr"]
    assert report.lens == theirs["lens"]
    assert "snr0" in report.fields() and "asnr" in dir(report)
    with pytest.raises(AttributeError, match="the fields are"):
        report.no_such_field  # noqa: B018


def test_errors_raise_scene_error_with_the_command_lines_message(tmp_path):
    with pytest.raises(asnr.SceneError) as e:
        asnr.load().with_({"lens.f_number": 0.1})
    assert str(e.value) == (
        "embedded paper scene (--set lens.f_number=0.1): lens.f_number = 0.1: expected a number ≥ 0.5 (NA = 1/(2F#) ≤ 1)"
    )
    with pytest.raises(asnr.SceneError, match="cannot read the scene file"):
        asnr.load(tmp_path / "missing.toml")
    with pytest.raises(asnr.SceneError, match="unknown field"):
        asnr.load().with_({"lens.no_such_key": 1})
    with pytest.raises(asnr.SceneError, match="malformed TOML"):
        asnr.load("[lens\nf_number = 2")
    with pytest.raises(TypeError, match="expected a number, a bool or a string"):
        asnr.load().with_({"lens.f_number": [1, 2]})
    with pytest.raises(TypeError):
        asnr.evaluate("examples/paper-theory.toml")
    with pytest.raises(asnr.SceneError, match="no detected signal"):
        asnr.load().with_({"camera.quantum_efficiency": 0.0})
    assert issubclass(asnr.SceneError, Exception)


def test_a_unit_slip_is_warned_about():
    with pytest.warns(asnr.SceneWarning, match="looks like mm"):
        asnr.evaluate(asnr.load().with_({"camera.pixel_pitch_um": 0.0052}))


# --- many points ---------------------------------------------------------------------------


MAP = ["--over", "lens.f_number=1.4:5:40", "--over", "spectrum.range_nm=2:300:100"]


def test_evaluate_many_over_the_map_is_the_sweep_csv_to_the_last_digit():
    over = {"lens.f_number": (1.4, 5, 40), "spectrum.range_nm": (2, 300, 100)}
    points = asnr.grid(over)
    result = asnr.evaluate_many(asnr.load(), points, threads=2)
    theirs = cli("sweep", *MAP, "--csv", "--threads", "2")
    assert asnr.to_csv(result).encode() == theirs
    # and the DataFrame of asnr.sweep holds the same numbers, column for column
    frame = asnr.sweep(asnr.load(), over, threads=2)
    assert list(frame.columns) == ["lens.f_number", "spectrum.range_nm", *asnr.RESULT_COLUMNS]
    assert np.array_equal(frame["asnr"].to_numpy(), result["asnr"])
    assert asnr.to_csv(frame).encode() == theirs


def test_evaluate_many_broadcasts_and_keeps_the_shape():
    f = np.array([[2.0], [3.0], [4.0]])
    r = np.array([10.0, 50.0])
    out = asnr.evaluate_many(asnr.load(), {"lens.f_number": f, "spectrum.range_nm": r})
    assert out["asnr"].shape == (3, 2) and out["fraunhofer_valid"].dtype == bool
    one = asnr.evaluate(asnr.load().with_({"lens.f_number": 3.0, "spectrum.range_nm": 50.0}))
    assert out["asnr"][1, 1] == one.asnr and out["snr0"][1, 1] == one.snr0
    assert out["lens.f_number"][2, 0] == 4.0 and out["spectrum.range_nm"][2, 1] == 50.0


def test_evaluate_many_names_the_point_that_fails():
    with pytest.raises(asnr.SceneError, match=r"at point 1 \(lens.f_number=0.2\).*expected a number ≥ 0.5"):
        asnr.evaluate_many(asnr.load(), {"lens.f_number": [2.0, 0.2, 3.0]})
    with pytest.raises(asnr.SceneError, match="expected finite numbers"):
        asnr.evaluate_many(asnr.load(), {"lens.f_number": [2.0, np.nan]})
    with pytest.raises(ValueError, match="shape mismatch|broadcast"):
        asnr.evaluate_many(asnr.load(), {"lens.f_number": [2.0, 3.0], "spectrum.range_nm": [1.0, 2.0, 3.0]})


def test_ctrl_c_stops_evaluate_many_between_chunks():
    # 200 000 points take minutes; an interrupt 0.3 s in must stop it after the running chunk
    f = np.linspace(1.4, 5.0, 200_000)
    timer = threading.Timer(0.3, _thread.interrupt_main)
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            asnr.evaluate_many(asnr.load(), {"lens.f_number": f}, threads=2, chunk=64)
    finally:
        timer.cancel()


def test_mtf_is_the_command_lines_curve():
    scene = asnr.load(PAPER)
    rows = cli("mtf", str(PAPER), "--csv", "--points", "11").decode().splitlines()
    header = rows[0].split(",")
    table = np.array([[float(x) for x in r.split(",")] for r in rows[1:]])
    nu = table[:, header.index("frequency_cyc_per_mm")]
    ours = asnr.mtf(scene, nu, wavelengths_nm=[800])
    assert np.allclose(ours["mtf"], table[:, header.index("mtf")], rtol=1e-12, atol=1e-15)
    assert ours["mtf"][0] == pytest.approx(1.0)
    assert ours["monochromatic"].shape == (1, 11)
    # any shape in, that shape out
    grid = asnr.mtf(scene, np.full((2, 3), 40.0))
    assert grid["mtf"].shape == (2, 3) and np.all(grid["mtf"] == grid["mtf"][0, 0])
    with pytest.raises(asnr.SceneError, match="finite frequencies ≥ 0"):
        asnr.mtf(scene, [-1.0])


def test_compare_is_the_command_lines_report():
    ours = asnr.compare(over="spectrum.range_nm=10:100:3", threads=2)
    theirs = json.loads(cli("compare", "--json", "--over", "spectrum.range_nm=10:100:3", "--threads", "2"))
    assert ours == theirs
    assert len(ours["designs"]) >= 4
    # overrides as a dict are written as Scene.with_ writes them, as a list as typed
    set_ = {"designs[1].lens.f_number": 4}
    ours = asnr.compare(set=set_, over="spectrum.range_nm=10:100:3", threads=2)
    theirs = cli("compare", "--json", "--set", "designs[1].lens.f_number=4", "--over", "spectrum.range_nm=10:100:3")
    assert ours == json.loads(theirs)
    assert asnr.compare(set=["designs[1].lens.f_number=4"], over="spectrum.range_nm=10:100:3", threads=2) == ours


# --- a lens written in Python --------------------------------------------------------------


class Chromatic(asnr.LensModel):
    """The paper's chromatic metalens: f(λ) = f0 λ0/λ, so W020(λ) = (1 − λ/λ0) f0/(8 F#²)."""

    def __init__(self, f_number=2.5, focal_length_m=3.36e-3, design_wavelength_m=800e-9, efficiency=0.15):
        self.f_number = f_number
        self.focal_length_m = focal_length_m
        self.design_wavelength_m = design_wavelength_m
        self.efficiency = efficiency

    def orders(self, wavelength_m, field):
        w020 = (1 - wavelength_m / self.design_wavelength_m) * self.focal_length_m / (8 * self.f_number**2)
        return [asnr.Order(efficiency=self.efficiency, defocus_m=w020)]

    def transmission(self, wavelength_m):
        return 0.55


def test_a_python_lens_gives_the_file_lens_asnr():
    scene = asnr.load(PAPER)
    ours = asnr.evaluate(scene.with_lens(Chromatic()))
    theirs = asnr.evaluate(scene)
    # different engines (the file's lens promises an affine defocus: closed form; the Python
    # lens goes through spectral quadrature), each within the scene's tolerance 1e-6
    assert ours.asnr == pytest.approx(theirs.asnr, rel=3e-6)
    assert ours.glare["m0"] == pytest.approx(theirs.glare["m0"], rel=1e-9)
    assert "(Python)" in ours.lens
    many = asnr.evaluate_many(scene.with_lens(Chromatic()), {"spectrum.range_nm": [10.0, 50.0]})
    assert many["asnr"][1] == ours.asnr


def test_relative_illumination_reaches_a_dict_with_and_a_python_lens():
    """cos⁴θ at 10°: the signal falls by cos⁴10° = 0.940609, as `asnr evaluate` says."""
    import math
    import tomllib

    as_dict = tomllib.loads(PAPER.read_text())
    as_dict["lens"]["relative_illumination"] = "cos4"
    as_dict["field"] = {"x_deg": 10.0}
    ours = asnr.evaluate(asnr.load(as_dict))
    theirs = json.loads(
        cli("evaluate", str(PAPER), "--json", "--set", "field.x_deg=10", "--set", 'lens.relative_illumination="cos4"')
    )
    # the same report but for the scene's name (a dict has none of its own)
    assert {k: v for k, v in ours.to_dict().items() if k != "scene"} == {
        k: v for k, v in theirs.items() if k != "scene"
    }
    assert ours.relative_illumination["model"] == "cos4"
    plain = asnr.load(PAPER).with_({"field.x_deg": 10.0})
    off = asnr.evaluate(plain).photoelectrons
    assert ours.photoelectrons / off == pytest.approx(math.cos(math.radians(10)) ** 4, rel=1e-14)
    # with_ and a Python lens: the key is the scene's, not the lens model's
    python_lens = plain.with_lens(Chromatic()).with_({"lens.relative_illumination": "cos4"})
    report = asnr.evaluate(python_lens)
    assert report.relative_illumination["factor"] == pytest.approx(math.cos(math.radians(10)) ** 4, rel=1e-15)


class ChromaticZ11(Chromatic):
    """The chromatic lens with 0.05 µm RMS of Z11 (Noll), given as Zernike terms."""

    def orders(self, wavelength_m, field):
        (order,) = super().orders(wavelength_m, field)
        return [dataclasses.replace(order, zernike_noll_m=(0.0,) * 10 + (0.05e-6,))]


def test_a_python_lens_takes_zernike_terms_as_the_file_lens_does(tmp_path):
    # the same Z11 through the scene file's key: both go through the radial engine
    scene = asnr.load(PAPER)
    ours = asnr.evaluate(scene.with_lens(ChromaticZ11()))
    text = PAPER.read_text(encoding="utf-8").replace(
        "transmission = 0.55", "zernike_noll_rms_um = [0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0.05]\ntransmission = 0.55", 1
    )
    (tmp_path / "z11.toml").write_text(text, encoding="utf-8")
    theirs = asnr.evaluate(asnr.load(tmp_path / "z11.toml"))
    plain = asnr.evaluate(scene)
    assert ours.mean_mtf == pytest.approx(theirs.mean_mtf, rel=3e-6)
    assert ours.mean_mtf < plain.mean_mtf


def test_a_python_lens_error_is_raised_by_the_evaluation():
    class Broken(Chromatic):
        def orders(self, wavelength_m, field):
            raise RuntimeError("no orders today")

    with pytest.raises(RuntimeError, match="no orders today"):
        asnr.evaluate(asnr.load().with_lens(Broken()))

    class Bad(Chromatic):
        def orders(self, wavelength_m, field):
            return [asnr.Order(efficiency=1.5, defocus_m=0.0)]

    with pytest.raises(ValueError, match="efficiency = 1.5: expected a fraction in"):
        asnr.evaluate(asnr.load().with_lens(Bad()))
    with pytest.raises(TypeError, match="f_number and focal_length_m"):
        asnr.load().with_lens(object())
    with pytest.raises(asnr.SceneError, match="its keys are set in Python"):
        asnr.load().with_lens(Chromatic()).with_({"lens.f_number": 2})


# --- scale-out -----------------------------------------------------------------------------


def test_a_scene_pickles_with_its_overrides_and_lens():
    scene = asnr.load(PAPER).with_({"spectrum.range_nm": 30})
    again = pickle.loads(pickle.dumps(scene))
    assert asnr.evaluate(again).to_dict() == asnr.evaluate(scene).to_dict()
    lens = asnr.load().with_lens(Chromatic(f_number=3.0))
    assert asnr.evaluate(pickle.loads(pickle.dumps(lens))).asnr == asnr.evaluate(lens).asnr


def evaluate_batch(scene, batch):
    """One Dask task: evaluate_many on one batch of points, one thread per worker."""
    return asnr.evaluate_many(scene, batch, threads=1)


def test_dask_local_cluster_reproduces_the_sweep_csv_byte_for_byte():
    distributed = pytest.importorskip("distributed")
    over = {"lens.f_number": (1.4, 5, 12), "spectrum.range_nm": (2, 300, 25)}
    points = asnr.grid(over)
    batches = [{k: v[i] for k, v in points.items()} for i in np.array_split(np.arange(300), 7)]
    scene = asnr.load()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the cluster's own chatter (ports, memory limits)
        with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
            with distributed.Client(cluster) as client:
                futures = client.map(evaluate_batch, [scene] * len(batches), batches)
                parts = client.gather(futures)
    csv = asnr.to_csv(asnr.concat(parts))
    theirs = cli("sweep", "--over", "lens.f_number=1.4:5:12", "--over", "spectrum.range_nm=2:300:25", "--csv")
    assert csv.encode() == theirs


def test_the_fig2b_example_runs_and_its_curve_is_the_sweeps(tmp_path):
    pytest.importorskip("matplotlib")
    script = ROOT / "examples" / "python" / "fig2b.py"
    done = subprocess.run(
        [sys.executable, str(script), "--out", str(tmp_path)],
        capture_output=True,
        check=False,
        cwd=ROOT,
        env={**os.environ, "MPLBACKEND": "Agg"},
    )
    assert done.returncode == 0, done.stderr.decode()
    assert (tmp_path / "fig2b.png").stat().st_size > 10_000
    theory = (tmp_path / "fig2b-theory.csv").read_bytes()
    assert theory == cli("sweep", "--set", "lens.f_number=2.5", "--over", "spectrum.range_nm=2:200:100", "--csv")


# --- designing with the ASNR ---------------------------------------------------------------


def test_optimize_is_the_command_lines_search_to_the_last_digit():
    scene = asnr.load()
    ours = asnr.optimize(scene, {"spectrum.range_nm": (1, 200), "spectrum.center_nm": (700, 900)})
    theirs = json.loads(cli("optimize", "--json", "--over", "spectrum.range_nm=1:200", "--over", "spectrum.center_nm=700:900"))
    assert ours == theirs
    assert abs(ours["best"]["spectrum.range_nm"] - 33.1) < 0.2
    assert ours["at_bound"] == {"spectrum.range_nm": False, "spectrum.center_nm": False}
    # one key: today's golden-section search, its JSON as the command line prints it
    one = asnr.optimize(scene, {"spectrum.range_nm": (1, 200)}, xtol=1e-3)
    assert one == json.loads(cli("optimize", "--json", "--over", "spectrum.range_nm=1:200", "--xtol", "1e-3"))
    with pytest.raises(asnr.SceneError, match="LO = 3 must be below HI = 2"):
        asnr.optimize(scene, {"lens.f_number": (3, 2), "spectrum.range_nm": (1, 2)})


def test_tolerance_is_the_command_lines_run_to_the_last_digit():
    scene = asnr.load().with_({"spectrum.range_nm": 40})
    vary = {"lens.f_number": "normal:2%", "spectrum.center_nm": "uniform:790:810"}
    ours = asnr.tolerance(scene, vary, n=300, seed=9, threads=2)
    args = ["tolerance", "--set", "spectrum.range_nm=40", "--vary", "lens.f_number=normal:2%"]
    args += ["--vary", "spectrum.center_nm=uniform:790:810", "--samples", "300", "--seed", "9"]
    theirs = json.loads(cli(*args, "--json"))
    assert {k: v for k, v in ours.items() if k not in ("csv", "table")} == theirs
    assert ours["csv"].encode() == cli(*args, "--csv")
    assert ours["table"]["asnr"].shape == (300,)
    assert float(np.mean(ours["table"]["asnr"])) == pytest.approx(ours["mean"], rel=1e-12)
    with pytest.raises(asnr.SceneError, match="unknown distribution `gamma`"):
        asnr.tolerance(scene, {"lens.f_number": "gamma:2"})
