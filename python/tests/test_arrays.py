"""Designs given as numpy arrays: `Scene.with_phase_map`, `Scene.with_layout` and arrays in
`Scene.with_` for `lens.phase_map`, `lens.amplitude_map` and `lens.layout_grid`.

An array is read as the `.npy` file holding it would be (the same checks, the same messages
naming the key), so each scene given arrays must equal, to 1e-12, the scene whose keys name the
arrays saved with `np.save`.
"""

from __future__ import annotations

import pickle
from pathlib import Path

import numpy as np
import pytest

import asnr
from scenes import NOT_THE_LENS


#: A small geometric-phase metalens (F/2.5, f0 = 125 µm, R = 25 µm, λ0 = 800 nm: the OTF depends
#: on ν λ F# only) on 0.5 µm cells, so that a map of 104 × 104 cells covers it and each
#: evaluation is quick.
F0_UM = 125.0
RADIUS_UM = 25.0
PITCH_UM = 0.5
N = 104


def scene_text(lens_keys: str) -> str:
    return f"""
[lens]
model = "phase"
f_number = 2.5
focal_length_mm = {F0_UM * 1e-3}
design_wavelength_nm = 800.0
dispersion = "geometric-phase"
efficiency = 0.15
transmission = 0.55
{lens_keys}
{NOT_THE_LENS}"""


#: The same lens given by its Binary 2 phase (the hyperbolic profile's first term): the scene a
#: user starts from before giving the map.
BINARY2_KEYS = f"binary2 = [{-2 * np.pi / 0.8 * RADIUS_UM**2 / (2 * F0_UM)!r}]\nnorm_radius_mm = {RADIUS_UM * 1e-3}"


def cubic_map() -> tuple[np.ndarray, np.ndarray]:
    """The hyperbolic phase plus 3 rad of (x/R)³ + (y/R)³, wrapped to [0, 2π) as a geometric-phase
    metasurface holds it, and an amplitude map falling to 0.8 at the corners: float64 [y, x]."""
    c = (np.arange(N) - 0.5 * (N - 1)) * PITCH_UM
    x, y = np.meshgrid(c, c)
    phase = -2 * np.pi / 0.8 * (np.sqrt(x * x + y * y + F0_UM**2) - F0_UM)
    phase += 3.0 * ((x / RADIUS_UM) ** 3 + (y / RADIUS_UM) ** 3)
    amplitude = 1.0 - 0.2 * (x * x + y * y) / (2 * (0.5 * N * PITCH_UM) ** 2)
    return np.mod(phase, 2 * np.pi), amplitude


def same(a: asnr.Report, b: asnr.Report) -> None:
    for field in ("asnr", "mean_mtf", "mean_mtf_tangential", "mean_mtf_sagittal", "snr0", "photoelectrons"):
        assert getattr(a, field) == pytest.approx(getattr(b, field), rel=1e-12, abs=0), field


def test_a_phase_map_given_as_arrays_equals_the_same_map_saved_as_npy(tmp_path):
    phase, amplitude = cubic_map()
    np.save(tmp_path / "phase.npy", phase)
    np.save(tmp_path / "amplitude.npy", amplitude)
    map_keys = f'phase_map = "phase.npy"\namplitude_map = "amplitude.npy"\nphase_map_pitch_um = {PITCH_UM}'
    (tmp_path / "files.toml").write_text(scene_text(map_keys))
    files = asnr.evaluate(asnr.load(tmp_path / "files.toml"))

    # from a scene whose lens is given by Binary 2 terms: the map replaces them
    base = asnr.load(scene_text(BINARY2_KEYS))
    given = base.with_phase_map(phase, pitch_um=PITCH_UM, amplitude=amplitude)
    same(asnr.evaluate(given), files)
    assert "lens.binary2" not in given.to_toml() and "binary2" not in given.to_toml()
    assert "<numpy float64 array 104 × 104>" in given.to_toml()
    # float32 (one copy, widened as a .npy of float32 is read) and Fortran order
    np.save(tmp_path / "phase32.npy", phase.astype(np.float32))
    (tmp_path / "files32.toml").write_text(scene_text(map_keys.replace("phase.npy", "phase32.npy")))
    files32 = asnr.evaluate(asnr.load(tmp_path / "files32.toml"))
    same(asnr.evaluate(base.with_phase_map(phase.astype(np.float32), pitch_um=PITCH_UM, amplitude=amplitude)), files32)
    same(asnr.evaluate(base.with_phase_map(np.asfortranarray(phase), pitch_um=PITCH_UM, amplitude=amplitude)), files)
    # the same keys through with_, and from the file scene itself (a later array replaces a file)
    through_with = asnr.load(tmp_path / "files.toml").with_({"lens.phase_map": phase, "lens.amplitude_map": amplitude})
    same(asnr.evaluate(through_with), files)
    # a scene with arrays pickles with them (Dask sends scenes to workers)
    same(asnr.evaluate(pickle.loads(pickle.dumps(given))), files)
    # a square aperture, given as the keyword
    (tmp_path / "square.toml").write_text(scene_text(map_keys + '\naperture = "square"'))
    square = asnr.evaluate(asnr.load(tmp_path / "square.toml"))
    same(asnr.evaluate(base.with_phase_map(phase, pitch_um=PITCH_UM, amplitude=amplitude, aperture="square")), square)
    assert square.photoelectrons == pytest.approx(4 / np.pi * files.photoelectrons, rel=1e-3)


def test_arrays_are_refused_as_their_files_are_naming_the_key(tmp_path):
    phase, amplitude = cubic_map()
    base = asnr.load(scene_text(BINARY2_KEYS))
    # the same message as the file's, the array named in place of the file
    bad = phase.copy()
    bad[N // 2, N // 2] = np.nan
    np.save(tmp_path / "bad.npy", bad)
    (tmp_path / "bad.toml").write_text(scene_text(f'phase_map = "bad.npy"\nphase_map_pitch_um = {PITCH_UM}'))
    with pytest.raises(asnr.SceneError) as from_file:
        asnr.load(tmp_path / "bad.toml")
    with pytest.raises(asnr.SceneError) as from_array:
        base.with_phase_map(bad, pitch_um=PITCH_UM)
    for e in (from_file, from_array):
        assert "lens.phase_map" in str(e.value) and "[y, x] = [52, 52]" in str(e.value), str(e.value)
    assert "<numpy float64 array 104 × 104>" in str(from_array.value)
    cases = [
        (lambda: base.with_phase_map(phase[:40, :40], pitch_um=PITCH_UM), ["lens.phase_map", "covering the aperture"]),
        (lambda: base.with_phase_map(phase, pitch_um=PITCH_UM, amplitude=amplitude[:-1]), ["lens.amplitude_map", "103 × 104"]),
        (lambda: base.with_phase_map(phase[0], pitch_um=PITCH_UM), ["lens.phase_map", "expected 2 axes [y, x]"]),
        (lambda: base.with_phase_map(phase, pitch_um=-1.0), ["lens.phase_map_pitch_um", "> 0"]),
        (lambda: base.with_phase_map(phase, pitch_um=8.0), ["lens.phase_map_pitch_um", "more than π"]),
    ]
    for make, words in cases:
        with pytest.raises(asnr.SceneError) as e:
            make()
        assert all(w in str(e.value) for w in words), (words, str(e.value))
    with pytest.raises(TypeError, match="lens.phase_map: a list: expected a numpy float array"):
        base.with_phase_map([[0.0, 1.0], [1.0, 0.0]], pitch_um=PITCH_UM)
    with pytest.raises(TypeError, match="lens.layout_grid: a ndarray: expected a numpy float array"):
        base.with_layout(np.zeros((4, 4), dtype=np.int64), pitch_um=0.4)
