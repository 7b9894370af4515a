"""A GDS drawn by gdstk, read by `lens.layout_gds`, against the radial library lens it draws.

The layout follows `examples/library.toml`'s, on the small lens of the project's own test of
2-D layouts (scene/tests/layout2d.rs, which writes its GDS with the project's writer): the
example's library (`examples/data/library-tio2-like.csv`), rings of 400 nm, each the diameter whose
field at 800 nm is nearest the hyperbolic phase at the ring's centre (the rule of `cargo xtask
data`), on a lens of the same F-number (F/2.5, f0 = 125 µm, R = 25 µm: the OTF depends on ν λ F#
only, and a 127 × 127 lattice keeps the test fast). Each lattice site holds the atom of the ring
its centre falls in. gdstk writes it twice, as a designer's tools do:

- every pillar a 9-vertex polygon with its vertices on the circle, as DFlat writes them;
- one cell per diameter (a pillar drawn at half size) placed by cell references: runs of equal
  atoms along a row as arrays (AREF), single atoms as references (SREF) turned by multiples of
  40° and 90° and magnified 2×, so that the reader's transforms are exercised.

Both must give the radial library lens's mean MTF and τ1 (the photoelectrons, N ∝ τ1) within the
lattice error the Rust test states, 2(1 − S_min) (docs/physics.md, "2-D library layouts"), and
each other's to the polygons' rounding on the 1 nm grid.

gdstk is required where `ASNR_REQUIRE` names it (`cargo xtask python`), else the test is skipped.
"""

from __future__ import annotations

import importlib
import os
from pathlib import Path

import numpy as np
import pytest

import asnr
from scenes import NOT_THE_LENS, ROOT

LIBRARY = ROOT / "examples" / "data" / "library-tio2-like.csv"
REQUIRED = {name.strip() for name in os.environ.get("ASNR_REQUIRE", "").split(",") if name.strip()}

F0_NM = 125e3
RADIUS_NM = 25e3
PITCH_NM = 400.0


def require(name: str):
    """The module `name`; skipped if it is missing, unless `ASNR_REQUIRE` names it."""
    if name in REQUIRED:
        return importlib.import_module(name)
    return pytest.importorskip(name)


def rings(f0_nm: float = F0_NM, radius_nm: float = RADIUS_NM) -> list[float]:
    """Ring i's diameter: the library's field at 800 nm nearest the hyperbolic phase at (i + ½) p."""
    table = np.loadtxt(LIBRARY, delimiter=",", comments="#", skiprows=3)
    at_800 = table[table[:, 1] == 800.0]
    field = at_800[:, 2] * np.exp(1j * at_800[:, 3])
    n = round(radius_nm / PITCH_NM) + 1
    out = []
    for i in range(n):
        r = (i + 0.5) * PITCH_NM
        target = -2 * np.pi / 800.0 * (np.sqrt(r * r + f0_nm * f0_nm) - f0_nm)
        out.append(float(at_800[np.argmin(np.abs(field - np.exp(1j * target))), 0]))
    return out


def sites(f0_nm: float = F0_NM, radius_nm: float = RADIUS_NM) -> np.ndarray:
    """The diameter at each lattice site [y, x] (NaN outside the drawn disc, one pitch beyond the
    aperture); an odd side, a site on the axis."""
    ring = rings(f0_nm, radius_nm)
    half = int(np.ceil(radius_nm / PITCH_NM)) + 1
    n = 2 * half + 1
    grid = np.full((n, n), np.nan)
    for j in range(n):
        for i in range(n):
            r = np.hypot((i - half) * PITCH_NM, (j - half) * PITCH_NM)
            if r <= radius_nm + PITCH_NM:
                grid[j, i] = ring[min(int(r / PITCH_NM), len(ring) - 1)]
    return grid


def pillar(diameter_nm: float, centre_um: tuple[float, float] = (0.0, 0.0)) -> np.ndarray:
    """A pillar as DFlat draws it: 9 vertices on the circle of the diameter (µm)."""
    a = 2 * np.pi * np.arange(9) / 9
    r = 0.5e-3 * diameter_nm
    return np.column_stack([centre_um[0] + r * np.cos(a), centre_um[1] + r * np.sin(a)])


def write_polygons(gdstk, path: Path, grid: np.ndarray) -> None:
    """One cell, every pillar a 9-vertex polygon on layer 1 (µm units, 1 nm database unit)."""
    lib = gdstk.Library(unit=1e-6, precision=1e-9)
    cell = lib.new_cell("LENS")
    half = grid.shape[0] // 2
    for (j, i), d in np.ndenumerate(grid):
        if not np.isnan(d):
            centre = ((i - half) * PITCH_NM * 1e-3, (j - half) * PITCH_NM * 1e-3)
            cell.add(gdstk.Polygon(pillar(d, centre), layer=1, datatype=0))
    lib.write_gds(str(path))


def write_references(gdstk, path: Path, grid: np.ndarray) -> int:
    """One cell per diameter (its pillar drawn at half size), placed by references magnified 2×:
    a run of equal atoms along a row is one AREF, a lone atom an SREF turned by 40° or 90° (a
    9-gon's symmetry, and a turn the reader must apply to the vertices). Returns the number of
    arrays written."""
    lib = gdstk.Library(unit=1e-6, precision=1e-9)
    top = lib.new_cell("LENS")
    atoms = {}
    for d in sorted({float(d) for d in grid[~np.isnan(grid)]}):
        atoms[d] = lib.new_cell(f"PILLAR_{d:.1f}")
        atoms[d].add(gdstk.Polygon(pillar(0.5 * d), layer=1, datatype=0))
    half = grid.shape[0] // 2
    pitch_um = PITCH_NM * 1e-3
    arrays = 0
    for j in range(grid.shape[0]):
        i = 0
        while i < grid.shape[1]:
            d = grid[j, i]
            if np.isnan(d):
                i += 1
                continue
            run = 1
            while i + run < grid.shape[1] and grid[j, i + run] == d:
                run += 1
            origin = ((i - half) * pitch_um, (j - half) * pitch_um)
            if run > 1:
                top.add(gdstk.Reference(atoms[float(d)], origin, magnification=2, columns=run, rows=1, spacing=(pitch_um, 0)))
                arrays += 1
            else:
                turn = np.deg2rad(40.0 if (i + j) % 2 else 90.0)
                top.add(gdstk.Reference(atoms[float(d)], origin, rotation=turn, magnification=2))
            i += run
    lib.write_gds(str(path))
    return arrays


def scene_text(lens_keys: str, f0_nm: float = F0_NM) -> str:
    return f"""
[lens]
model = "library"
f_number = 2.5
focal_length_mm = {f0_nm * 1e-6}
design_wavelength_nm = 800.0
library = "{LIBRARY.as_posix()}"
{lens_keys}
{NOT_THE_LENS}
[options]
pupil_samples = 256
"""


def lattice_bound() -> float:
    """The stated lattice error: twice 1 − S_min, the cells' design-order amplitude
    sinc(g_x p/λ) sinc(g_y p/λ) at the aperture's edge on the diagonal at the band's short end
    (775 nm; docs/physics.md, "2-D library layouts"), as scene/tests/layout2d.rs states it."""
    c = RADIUS_NM / np.sqrt(2.0)
    g = c / np.hypot(RADIUS_NM, F0_NM)
    u = PITCH_NM / 775.0 * g
    return 2.0 * (1.0 - np.sinc(u) ** 2)


def test_a_gds_drawn_by_gdstk_reproduces_the_radial_library_lens(tmp_path):
    gdstk = require("gdstk")
    grid = sites()
    ring = rings()
    rows = "".join(f"{(i + 0.5) * PITCH_NM * 1e-6:.7f},{d:.1f}\n" for i, d in enumerate(ring))
    (tmp_path / "layout.csv").write_text("r_mm,diameter_nm\n" + rows)
    write_polygons(gdstk, tmp_path / "polygons.gds", grid)
    arrays = write_references(gdstk, tmp_path / "references.gds", grid)
    assert arrays > 100, arrays  # the rings' runs along rows: many AREFs

    def evaluate(lens_keys: str):
        (tmp_path / "scene.toml").write_text(scene_text(lens_keys))
        return asnr.evaluate(asnr.load(tmp_path / "scene.toml"))

    radial = evaluate('layout = "layout.csv"')
    gds_keys = 'gds_layer = 1\ngds_cell = "LENS"\nlattice_pitch_um = 0.4'
    polygons = evaluate(f'layout_gds = "polygons.gds"\n{gds_keys}')
    references = evaluate(f'layout_gds = "references.gds"\n{gds_keys}')
    bound = lattice_bound()
    for name, e in [("polygons", polygons), ("references", references)]:
        tau = e.photoelectrons / radial.photoelectrons - 1.0
        print(f"{name}: mean MTF {e.mean_mtf:.5f} ({e.mean_mtf - radial.mean_mtf:+.2e}), τ1 {tau:+.2e} relative; bound {bound:.4f}")
        assert abs(e.mean_mtf - radial.mean_mtf) <= bound, (name, e.mean_mtf, radial.mean_mtf, bound)
        assert abs(tau) <= bound, (name, tau, bound)
    # the same atoms drawn two ways: equal to the polygons' rounding on the 1 nm grid (the
    # project's test measures the grid's diameters against such polygons within 2e-3 in τ1)
    assert references.photoelectrons == pytest.approx(polygons.photoelectrons, rel=2e-3)
    assert references.mean_mtf == pytest.approx(polygons.mean_mtf, abs=2e-3)


def test_a_layout_grid_given_as_an_array_equals_its_npy_file(tmp_path):
    """`Scene.with_layout` (and `with_` of `lens.layout_grid`) of the drawn layout equals the
    scene naming the grid saved with `np.save`, to 1e-12; it replaces the radial layout of the
    scene it starts from; a bad grid is refused naming the key, as the file is. The same layout
    rule on a lens of R = 10 µm (f0 = 50 µm, F/2.5): equality needs no large lens."""
    f0 = 50e3
    grid = sites(f0, 10e3)
    rows = "".join(f"{(i + 0.5) * PITCH_NM * 1e-6:.7f},{d:.1f}\n" for i, d in enumerate(rings(f0, 10e3)))
    (tmp_path / "layout.csv").write_text("r_mm,diameter_nm\n" + rows)
    np.save(tmp_path / "grid.npy", grid)
    (tmp_path / "grid.toml").write_text(scene_text('layout_grid = "grid.npy"\nlattice_pitch_um = 0.4', f0))
    (tmp_path / "radial.toml").write_text(scene_text('layout = "layout.csv"', f0))
    files = asnr.evaluate(asnr.load(tmp_path / "grid.toml"))
    radial = asnr.load(tmp_path / "radial.toml")
    # [parameter, y, x] of one parameter is the [y, x] grid: the same scene
    stacked = radial.with_layout(grid[None, :, :], pitch_um=0.4)
    assert stacked.overrides == radial.with_layout(grid, pitch_um=0.4).overrides
    for given in (stacked, asnr.load(tmp_path / "grid.toml").with_({"lens.layout_grid": grid})):
        e = asnr.evaluate(given)
        for field in ("asnr", "mean_mtf", "snr0", "photoelectrons"):
            assert getattr(e, field) == pytest.approx(getattr(files, field), rel=1e-12, abs=0), field
    assert "layout.csv" not in radial.with_layout(grid, pitch_um=0.4).to_toml()
    bad = grid.copy()
    bad[3, 40] = np.inf
    side = f"{grid.shape[0]} × {grid.shape[1]}"
    with pytest.raises(asnr.SceneError, match=rf"lens\.layout_grid.*<numpy float64 array {side}>.*site \(40, 3\) is infinite"):
        radial.with_layout(bad, pitch_um=0.4)
    with pytest.raises(asnr.SceneError, match=r"lens\.layout_grid.*expected 2 axes"):
        radial.with_layout(np.stack([grid, grid]), pitch_um=0.4)
