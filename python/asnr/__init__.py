"""How good is this metalens, really? The ASNR of a lens, light, camera and exposure.

The `asnr` command line's computation from Python: a scene is read once (a scene file, TOML
text or a dict), changed with :meth:`Scene.with_`, and evaluated at one point
(:func:`evaluate`), at many (:func:`evaluate_many`, numpy arrays in and out, in parallel with the
GIL released), over a grid (:func:`sweep`, a pandas DataFrame), or compared with other designs
(:func:`compare`). :func:`mtf` gives the polychromatic MTF; :func:`optimize` searches the keys
that maximize the ASNR and :func:`tolerance` samples how it survives fabrication errors.
:func:`gradient` is the exact gradient of the ASNR with respect to scene keys (``asnr gradient``),
and :func:`value_and_grad` the objective and its gradient as a function of a numpy vector (for
``scipy.optimize.minimize(jac=True)``); ``asnr.jax`` and ``asnr.torch`` make the ASNR a
differentiable function of a JAX array or a torch tensor. :func:`sfr` measures the MTF of slanted
edges in camera frames and :func:`measure` the SNR and the measured ASNR of a stack (``asnr sfr``,
``asnr measure``). Every number is the one ``asnr``
prints for the same scene (the same Rust functions compute it): ``evaluate_many`` over a grid
is ``asnr sweep --csv`` to the last digit, and :func:`to_csv` writes its bytes.

Errors raise :class:`SceneError` with the command line's message, which names the file (or the
override), the key, the value and what is accepted. Scene files, keys and units are those of the
repository's README ("Scene files"); frequencies are in cycles/mm, wavelengths in nm unless a
name says ``_m``.

A lens written in Python (:class:`LensModel`) replaces a scene's ``[lens]`` for prototyping.
"""

from __future__ import annotations

import dataclasses
import json
import os
import warnings
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np

from . import _asnr
from ._asnr import Scene, SceneError

__all__ = [
    "LensModel",
    "Order",
    "Report",
    "Scene",
    "SceneError",
    "SceneWarning",
    "RESULT_COLUMNS",
    "axis",
    "compare",
    "concat",
    "evaluate",
    "evaluate_many",
    "gradient",
    "grid",
    "load",
    "measure",
    "mtf",
    "optimize",
    "sfr",
    "sweep",
    "to_csv",
    "tolerance",
    "value_and_grad",
    "ValueAndGrad",
]

__version__ = "0.1.0"

#: The result columns of a sweep, after the swept keys' (as ``asnr sweep --csv`` writes them).
RESULT_COLUMNS = ("mean_mtf", "snr0", "asnr", "photoelectrons", "fraunhofer_valid", "warnings")


class SceneWarning(UserWarning):
    """A scene value that is valid but looks like a unit slip (e.g. a pixel pitch in mm)."""


def load(scene: str | os.PathLike[str] | Mapping[str, Any] | None = None, *, directory: str | os.PathLike[str] | None = None) -> Scene:
    """Reads a scene.

    ``scene`` is a path to a scene file (``str`` or ``pathlib.Path``), TOML text (a ``str``
    holding a newline or ``=``), a dict of the file's tables (``{"lens": {"f_number": 2.5}, …}``)
    or ``None`` for the paper's chromatic metalens (embedded, ``examples/paper-theory.toml``).
    CSV paths in TOML text or a dict resolve against ``directory`` (default: the current folder).
    Raises :class:`SceneError` if it is not a valid scene.
    """
    base = os.fspath(directory) if directory is not None else os.getcwd()
    if scene is None:
        return _asnr.load_file(None)
    if isinstance(scene, Mapping):
        return _asnr.load_json(json.dumps(scene, allow_nan=True), "scene dict", base)
    if isinstance(scene, str) and ("\n" in scene or "=" in scene):
        return _asnr.load_text(scene, "scene text", base)
    if isinstance(scene, (str, os.PathLike)):
        return _asnr.load_file(os.fspath(scene))
    raise TypeError(f"load: a {type(scene).__name__}: expected a path, TOML text, a dict or None")


class Report:
    """One evaluation: the fields of ``asnr evaluate --json`` as attributes (``asnr``, ``snr0``,
    ``mean_mtf``, ``photoelectrons``, ``fraunhofer``, ``glare``, ``noise``, ``numerics``,
    ``warnings``, ``scene``, ``title``, ``lens``, …)."""

    def __init__(self, report: dict[str, Any]):
        self._report = report

    def __getattr__(self, name: str) -> Any:
        report = self.__dict__.get("_report", {})
        if name in report:
            return report[name]
        raise AttributeError(f"Report has no field {name!r}; the fields are {self.fields()}")

    def fields(self) -> list[str]:
        """The names of the report's fields, in the JSON's order."""
        return list(self._report)

    def __dir__(self) -> list[str]:
        return sorted(set(super().__dir__()) | set(self.fields()))

    def to_dict(self) -> dict[str, Any]:
        """The report as ``asnr evaluate --json`` prints it (a copy)."""
        return json.loads(json.dumps(self._report))

    def __repr__(self) -> str:
        r = self._report
        return f"Report(asnr={r['asnr']:.6g}, snr0={r['snr0']:.6g}, mean_mtf={r['mean_mtf']:.6g}, lens={r['lens']!r})"


def _warn(messages: Iterable[str]) -> None:
    for m in messages:
        warnings.warn(m, SceneWarning, stacklevel=3)


def evaluate(
    scene: Scene,
    *,
    metrics: bool = False,
    object: str | None = None,  # noqa: A002 - the command line's name
    contrast: float | None = None,
    frame_rate_hz: float | None = None,
    task: str | None = None,
) -> Report:
    """The ASNR of ``scene`` and how it was computed (the report of ``asnr evaluate --json``).

    With ``metrics=True`` (implied by any of the four options after it) the report also has the
    fields of ``asnr evaluate --metrics --json``: ``neq`` (the curve), ``mean_neq``,
    ``neq_zero``, ``capacity_bits_per_pixel`` (Fellgett–Linfoot, for the ``object`` spectrum
    ``"flat"`` or ``"power-law:BETA"`` at ``contrast``, default 1) with
    ``capacity_error_bits`` and ``capacity_perfect_lens_bits_per_pixel``,
    ``capacity_bits_per_pixel_per_second`` (with ``frame_rate_hz``), ``detectability`` (d′ of
    ``task``, ``"disk:DIAMETER_UM:CONTRAST"``) and ``ideal_lens`` (the ASNR of a
    diffraction-limited lens of the same aperture and the ratio); docs/physics.md, "Metrics
    beyond the ASNR", defines them.

    Values that look like a unit slip are warned about (:class:`SceneWarning`); the evaluation's
    own warnings are in ``report.warnings``."""
    words = (object, None if contrast is None else float(contrast), None if frame_rate_hz is None else float(frame_rate_hz), task)
    wanted = metrics or any(w is not None for w in words)
    text, _lens, scene_warnings = _asnr.evaluate(_scene(scene), words if wanted else None)
    _warn(scene_warnings)
    return Report(json.loads(text))


def _frames(what: str, images: Any) -> list[Any]:
    """Frames as the native module takes them: paths as strings, arrays as ``(name, float64
    array, bits)`` with the bits of their dtype (uint8: 8, uint16: 16, floating point: 32)."""
    if images is None:
        return []
    if isinstance(images, np.ndarray) and images.ndim == 3:
        images = list(images)  # a stack: frames along the first axis
    elif isinstance(images, (str, os.PathLike, np.ndarray)):
        images = [images]
    out: list[Any] = []
    for i, image in enumerate(images):
        if isinstance(image, (str, os.PathLike)):
            out.append(os.fspath(image))
            continue
        array = np.asarray(image)
        if array.ndim != 2:
            raise ValueError(f"{what}[{i}]: an array of shape {array.shape}: expected one 2-D grayscale frame (rows, columns)")
        if array.dtype == np.uint8:
            bits = 8
        elif array.dtype == np.uint16:
            bits = 16
        elif np.issubdtype(array.dtype, np.floating):
            bits = 32
        else:
            raise ValueError(f"{what}[{i}]: an array of {array.dtype}: expected uint8, uint16 or floating-point grey levels")
        out.append((f"{what}[{i}] (array)", np.ascontiguousarray(array, dtype=np.float64), bits))
    return out


def _region(name: str, region: Any) -> str | None:
    """``X,Y,W,H`` as the command line takes it, from a string or four whole numbers."""
    if region is None or isinstance(region, str):
        return region
    values = list(region)
    if len(values) != 4:
        raise ValueError(f"{name}: {values!r}: expected X,Y,W,H (four whole numbers of pixels)")
    return ",".join(str(int(v)) if float(v).is_integer() else str(v) for v in values)


def sfr(
    images: Any,
    *,
    roi: str | Sequence[int] | None = None,
    dark: Any = None,
    gamma: float | None = None,
    transfer: str | os.PathLike[str] | None = None,
    pixel_pitch_um: float | None = None,
    curved: bool = False,
    reach: float | None = None,
) -> dict[str, Any]:
    """The MTF of slanted edges (ISO 12233 e-SFR): ``asnr sfr --json``'s fields, the same
    analysis and so the same numbers.

    ``images`` is one frame or a list of them, each a path (a PNG or TIFF file, a folder or a
    pattern, as the command line takes them) or a 2-D numpy array of grey levels (uint8 and
    uint16 arrays clip at their largest code, as 8- and 16-bit files do; floating point is a
    32-bit float TIFF's), or a 3-D array (frames along its first axis); several frames are averaged and their spread gives the standard errors.
    ``roi`` is ``"X,Y,W,H"`` or ``(x, y, w, h)`` in pixels (default the whole frame), ``dark``
    frames are subtracted, the response is linear, ``gamma`` or the ``transfer`` curve of
    ``asnr characterize --json``; ``pixel_pitch_um`` adds cycles/mm; ``curved`` fits a parabola;
    ``reach`` is the LSF's half-width in pixels.

    The dict has ``edges`` (one dict each) and, when the ROI holds one edge, its fields at the
    top level: ``mean_mtf`` (to Nyquist, the ASNR's factor) and ``mean_mtf_sigma``,
    ``mtf50_cyc_per_px``, ``mtf_nyquist``, ``edge_angle_deg``, ``frequency_cyc_per_px`` and
    ``mtf`` (arrays, as lists), … Bad input (no edge, two edges, an angle outside 1°–35°, a
    clipped edge, frames of different sizes, a ROI outside the frame) raises ``ValueError``
    with the command line's message, naming the file (or array) and the reason."""
    text = _asnr.sfr(
        _frames("images", images),
        _region("roi", roi),
        _frames("dark", dark),
        None if gamma is None else float(gamma),
        None if transfer is None else os.fspath(transfer),
        None if pixel_pitch_um is None else float(pixel_pitch_um),
        bool(curved),
        None if reach is None else float(reach),
    )
    return json.loads(text)


def measure(
    frames: Any,
    *,
    white: str | Sequence[int],
    black: str | Sequence[int],
    capped_black: Any = None,
    include_glare: bool = False,
    edge: Any = None,
    edge_roi: str | Sequence[int] | None = None,
    mtf_csv: str | os.PathLike[str] | None = None,
    pixel_pitch_um: float | None = None,
    compare: Scene | None = None,
) -> dict[str, Any]:
    """The SNR of a stack of frames (paper eq. 2–4) and, with an MTF, the measured ASNR:
    ``asnr measure --json``'s fields, the same computation and so the same numbers.

    ``frames`` (two or more) and ``capped_black`` are taken as :func:`sfr` takes images;
    ``white`` and ``black`` are the regions, ``"X,Y,W,H"`` or ``(x, y, w, h)``. The measured
    MTF comes from ``edge`` frames (their e-SFR, one edge, in ``edge_roi``) or a CSV table
    ``mtf_csv`` (``frequency_cyc_per_mm, mtf``; Nyquist from ``pixel_pitch_um`` or the scene).
    ``compare`` is a :class:`Scene` evaluated with the pixel aperture (``camera.pixel_mtf =
    true``), set beside the measured values with the ratios (``compare`` in the dict).

    The dict has ``snr``, ``snr_sigma``, ``signal``, ``white``, ``black``, ``sigma_*``, ``vg``,
    ``modulation``, …; ``measured_asnr`` (``asnr``, ``asnr_sigma``, ``mean_mtf``, ``snr``, …,
    ``mtf_source``, ``edge_angle_deg``) with an MTF. Bad input raises ``ValueError`` naming the
    file (or array) and the reason; a scene that cannot be evaluated, :class:`SceneError`."""
    if compare is not None:
        compare = _scene(compare)
    text = _asnr.measure(
        _frames("frames", frames),
        _region("white", white),
        _region("black", black),
        _frames("capped_black", capped_black),
        bool(include_glare),
        _frames("edge", edge),
        _region("edge_roi", edge_roi),
        None if mtf_csv is None else os.fspath(mtf_csv),
        None if pixel_pitch_um is None else float(pixel_pitch_um),
        compare,
    )
    return json.loads(text)


def _scene(scene: Any) -> Scene:
    if not isinstance(scene, Scene):
        raise TypeError(f"expected an asnr.Scene (asnr.load(...)), got a {type(scene).__name__}")
    return scene


def evaluate_many(scene: Scene, values: Mapping[str, Any], *, threads: int = 0, chunk: int = 256) -> dict[str, np.ndarray]:
    """The ASNR at many points: ``values`` maps dotted scene keys to arrays (broadcast together,
    numpy's rules); point ``i`` is the scene with every key at its ``i``-th value.

    Returns a dict of arrays of the broadcast shape: the keys' values, then ``mean_mtf``,
    ``snr0``, ``asnr``, ``photoelectrons`` (float64), ``fraunhofer_valid`` (bool) and ``warnings``
    (str, each point's warnings joined by ``" | "``). Runs on ``threads`` threads (0: all cores)
    with the GIL released, ``chunk`` points at a time; Ctrl-C stops it between chunks. Raises
    :class:`SceneError` at the first point that is not a valid scene, naming it."""
    scene = _scene(scene)
    if not values:
        raise ValueError("evaluate_many: no keys; expected a dict of dotted scene keys to arrays")
    keys = list(values)
    arrays = np.broadcast_arrays(*[np.asarray(values[k], dtype=np.float64) for k in keys])
    shape = arrays[0].shape
    columns = [np.ascontiguousarray(a, dtype=np.float64).ravel() for a in arrays]
    out = _asnr.evaluate_many(scene, keys, columns, threads, chunk)
    result: dict[str, np.ndarray] = {k: c.reshape(shape) for k, c in zip(keys, columns)}
    for name in RESULT_COLUMNS:
        column = out[name]
        result[name] = (np.array(column, dtype=object) if name == "warnings" else column).reshape(shape)
    return result


def axis(lo: float, hi: float, n: int) -> np.ndarray:
    """``n`` values from ``lo`` to ``hi``, both included, equally spaced: the floats of
    ``asnr sweep --over KEY=LO:HI:N`` (``np.linspace`` may differ in the last bit)."""
    return _asnr.axis(float(lo), float(hi), int(n))


def grid(over: Mapping[str, Any]) -> dict[str, np.ndarray]:
    """The points of a grid as flat arrays, the first key varying slowest (``asnr sweep``'s
    order): ``over`` maps each key to ``(lo, hi, n)`` (:func:`axis`) or to its values."""
    axes = []
    for key, spec in over.items():
        if isinstance(spec, tuple) and len(spec) == 3 and all(isinstance(x, (int, float)) for x in spec) and float(spec[2]).is_integer():
            axes.append(axis(*spec))
        else:
            values = np.asarray(spec, dtype=np.float64).ravel()
            if values.size == 0:
                raise ValueError(f"{key}: no values")
            axes.append(values)
    mesh = np.meshgrid(*axes, indexing="ij")
    return {k: m.ravel() for k, m in zip(over, mesh)}


def sweep(scene: Scene, over: Mapping[str, Any], *, threads: int = 0, frame: bool | None = None):
    """The ASNR over the cartesian product of ``over`` (see :func:`grid`), as ``asnr sweep``
    evaluates it: a pandas DataFrame with the CSV's columns (the keys, then
    :data:`RESULT_COLUMNS`) when pandas is installed (``frame=False``: a dict of arrays)."""
    result = evaluate_many(scene, grid(over), threads=threads)
    if frame is False:
        return result
    try:
        import pandas as pd
    except ImportError:
        if frame:
            raise
        return result
    return pd.DataFrame(result)


def concat(parts: Sequence[Mapping[str, np.ndarray]]) -> dict[str, np.ndarray]:
    """Results of :func:`evaluate_many` on batches (e.g. from Dask workers), joined in order."""
    if not parts:
        raise ValueError("concat: no results")
    return {k: np.concatenate([np.ravel(p[k]) for p in parts]) for k in parts[0]}


def to_csv(result: Any) -> str:
    """The CSV ``asnr sweep --csv`` writes for these points, byte for byte: ``result`` is what
    :func:`evaluate_many`, :func:`sweep` or :func:`concat` returned (a dict of arrays or a
    DataFrame); the columns before ``mean_mtf`` are the keys."""
    columns = list(result.keys())
    if "mean_mtf" not in columns:
        raise ValueError("to_csv: expected the result of evaluate_many or sweep (no mean_mtf column)")
    keys = columns[: columns.index("mean_mtf")]
    flat = {k: np.ravel(np.asarray(result[k])) for k in keys + list(RESULT_COLUMNS)}
    n = flat["asnr"].size
    rows = [
        (
            [float(flat[k][i]) for k in keys],
            float(flat["mean_mtf"][i]),
            float(flat["snr0"][i]),
            float(flat["asnr"][i]),
            float(flat["photoelectrons"][i]),
            bool(flat["fraunhofer_valid"][i]),
            str(flat["warnings"][i]),
        )
        for i in range(n)
    ]
    return _asnr.sweep_csv(keys, rows)


def mtf(scene: Scene, nu: Any, *, wavelengths_nm: Iterable[float] = ()) -> dict[str, Any]:
    """The polychromatic MTF of ``scene`` at the frequencies ``nu`` (cycles/mm, any shape):
    a dict with ``frequency`` (``nu``), ``mtf`` (times the pixel MTF if the camera applies it;
    the tangential–sagittal average where the OTF depends on direction, as the ASNR's mean is),
    ``otf`` (signed), ``diffraction_limited`` (at the mean wavelength), ``mtf_tangential`` and
    ``mtf_sagittal`` (or None), ``monochromatic`` (one row per wavelength of ``wavelengths_nm``),
    and ``nyquist``, ``mean_wavelength_nm``."""
    nu_array = np.asarray(nu, dtype=np.float64)
    flat = np.ascontiguousarray(nu_array).ravel()
    curve = json.loads(_asnr.mtf(_scene(scene), flat, [float(w) for w in wavelengths_nm]))
    shaped = lambda v: None if v is None else np.asarray(v, dtype=np.float64).reshape(nu_array.shape)  # noqa: E731
    return {
        "frequency": nu_array,
        "mtf": shaped(curve["mtf"]),
        "otf": shaped(curve["otf"]),
        "diffraction_limited": shaped(curve["diffraction_limited"]),
        "mtf_tangential": shaped(curve["mtf_tangential"]),
        "mtf_sagittal": shaped(curve["mtf_sagittal"]),
        "wavelengths_nm": np.asarray(curve["wavelengths_nm"], dtype=np.float64),
        "monochromatic": np.asarray(curve["monochromatic"], dtype=np.float64).reshape((len(curve["wavelengths_nm"]),) + nu_array.shape),
        "nyquist": curve["nyquist_cyc_per_mm"],
        "mean_wavelength_nm": curve["mean_wavelength_nm"],
        "pixel_mtf": curve["pixel_mtf"],
    }


def compare(
    path: str | os.PathLike[str] | None = None,
    *,
    set: Mapping[str, Any] | Sequence[str] | None = None,  # noqa: A002 - the command line's name
    tolerance: float | None = None,
    over: str | None = None,
    threads: int = 0,
) -> dict[str, Any]:
    """Lens designs side by side (``asnr compare --json``): the comparison file ``path`` (None:
    the embedded comparison of the lens families), overrides ``set`` (a dict, or ``key=value``
    strings; ``designs[1].lens.f_number`` reaches one design), each design's ASNR at the scene
    band and at its best band searched over ``over`` (``"spectrum.range_nm=LO:HI:N"``), its
    chromatic twin and glare."""
    overrides = dict(set) if isinstance(set, Mapping) else None if set is None else [str(s) for s in set]
    text, scene_warnings = _asnr.compare(None if path is None else os.fspath(path), overrides, tolerance, over, threads)
    _warn(scene_warnings)
    return json.loads(text)


def optimize(
    scene: Scene,
    over: Mapping[str, tuple[float, float]],
    *,
    objective: str = "asnr",
    xtol: float = 1e-4,
    starts: int | None = None,
    max_evaluations: int | None = None,
    method: str | None = None,
    tolerance: float | None = None,
) -> dict[str, Any]:
    """The values of scene keys that maximize the ASNR: ``asnr optimize --json`` with one
    ``--over KEY=LO:HI`` per entry of ``over`` (``{key: (lo, hi)}``), the same search and so the
    same numbers. One key: a 17-point scan and golden section (``best`` a number); several:
    COBYLA from the best of a Halton start set of ``starts`` points (default 10 per key), at
    most ``max_evaluations`` evaluations (default 500; ``best`` and ``at_bound`` dicts keyed by
    the keys, ``history`` every point evaluated). ``method``: ``"cobyla"`` (the default for
    several keys) or ``"gradient"`` (``--method gradient``: projected L-BFGS on the exact
    gradient, up to 64 keys, the keys :func:`gradient` differentiates; the dict adds
    ``gradient`` at the optimum). ``objective``: ``"asnr"``, ``"asnr_glare"`` (SI eq. S14),
    ``"fov_mean"`` or ``"worst_channel"`` (not with ``method="gradient"``). ``tolerance``:
    ``--tolerance``, the relative error allowed in each ASNR (``options.tolerance``)."""
    scene = _scene(scene)
    if tolerance is not None:
        scene = scene.with_({"options.tolerance": float(tolerance)})
    ranges = [(str(k), float(lo), float(hi)) for k, (lo, hi) in over.items()]
    text = _asnr.optimize(
        scene,
        ranges,
        objective,
        float(xtol),
        0 if starts is None else int(starts),
        500 if max_evaluations is None else int(max_evaluations),
        None if method is None else str(method),
    )
    return json.loads(text)


def _keys(keys: str | Iterable[str]) -> list[str]:
    """One key or several, as a list of strings (a lone string is one key, not its letters)."""
    out = [keys] if isinstance(keys, str) else [str(k) for k in keys]
    if not out:
        raise ValueError("no key to differentiate with respect to: give one or more dotted scene keys")
    return out


def gradient(
    scene: Scene,
    keys: str | Iterable[str],
    *,
    set: Mapping[str, Any] | Sequence[str] | None = None,  # noqa: A002 - the command line's name
    tolerance: float | None = None,
) -> dict[str, Any]:
    """The exact gradient of the ASNR, mean MTF, SNR0 and photoelectrons with respect to scene
    keys: ``asnr gradient --json`` with one ``--wrt KEY`` per entry of ``keys`` (one key, or a
    list; ``"lens.binary2"`` means every entry, spelled ``lens.binary2[0]``, …), the overrides
    ``set`` (a dict, or ``key=value`` strings as ``--set`` takes them) after the scene's own, and
    ``tolerance`` (``--tolerance``: the relative error allowed in the mean MTF and its
    derivatives). The same function computes it, so the dict is the command line's JSON: ``asnr``,
    ``mean_mtf``, ``snr0``, ``photoelectrons``, and ``gradient``, ``mean_mtf_gradient``,
    ``snr0_gradient``, ``photoelectrons_gradient``, each ``{KEY: derivative}`` (per unit of the
    key: per ms for ``exposure.time_ms``, per radian for ``lens.binary2[i]``) in the order of the
    keys, each key spelled one canonical way.

    Computed inside the engines (docs/physics.md, "Gradients"), never by finite differences: a
    key the value does not depend on smoothly (an integer, a switch, a seed), one whose derivative
    is not computed yet, an unknown key, a key the scene lacks or a key given twice raises
    :class:`SceneError` naming the key."""
    overrides: Any = None
    if set is not None:
        overrides = dict(set) if isinstance(set, Mapping) else [str(s) for s in set]
    text, _values = _asnr.gradient(_scene(scene), _keys(keys), overrides, None if tolerance is None else float(tolerance))
    return json.loads(text)


class ValueAndGrad:
    """The objective of a scene as a function of a vector of its keys' values, and its exact
    gradient: ``f(x)`` returns ``(value, gradient)``, a float and a float64 array of the keys'
    length, the form ``scipy.optimize.minimize(fun, x0, jac=True)`` takes (negate both to
    minimize: ``lambda x: tuple(-v for v in f(x))``, or build it with ``sign=-1``).

    Made by :func:`value_and_grad`. ``keys`` are the keys, one entry each (``lens.binary2`` given
    as a whole is spelled out), ``x0`` their values in the scene, ``objective`` the objective's
    name; :meth:`value` is the objective alone (one evaluation, cheaper than its gradient)."""

    def __init__(self, scene: Scene, keys: list[str], x0: np.ndarray, objective: str, sign: float):
        self.scene = scene
        self.keys = keys
        self.x0 = x0
        self.objective = objective
        self.sign = sign

    def _values(self, x: Any) -> np.ndarray:
        values = np.ascontiguousarray(np.asarray(x, dtype=np.float64).reshape(-1))
        if values.shape != (len(self.keys),):
            raise ValueError(f"{np.shape(x)}: expected a 1-D array of {len(self.keys)} values, one per key ({', '.join(self.keys)})")
        return values

    def __call__(self, x: Any) -> tuple[float, np.ndarray]:
        value, grad = _asnr.objective_value_and_gradient(self.scene, self.keys, self._values(x), self.objective)
        return self.sign * value, self.sign * grad

    def value(self, x: Any) -> float:
        """The objective at ``x`` without its gradient (times ``sign``)."""
        return self.sign * _asnr.objective_value(self.scene, self.keys, self._values(x), self.objective)

    def __repr__(self) -> str:
        return f"ValueAndGrad(objective={self.objective!r}, keys={self.keys!r}, sign={self.sign:+g})"


def value_and_grad(
    scene: Scene,
    keys: str | Iterable[str],
    objective: str = "asnr",
    *,
    tolerance: float | None = None,
    sign: float = 1.0,
) -> ValueAndGrad:
    """The objective of ``scene`` (``"asnr"``, ``"asnr_glare"`` or ``"fov_mean"``, as ``asnr
    optimize --objective`` takes them) as a function of the values of ``keys``:
    ``f = asnr.value_and_grad(scene, keys)``; ``f(x)`` returns ``(value, gradient)`` with ``x``,
    the gradient a numpy float64 array, one entry per key in the order of ``f.keys``, per unit of
    each key. ``sign=-1`` returns −value and −gradient, for a minimizer:
    ``scipy.optimize.minimize(asnr.value_and_grad(scene, keys, sign=-1), f.x0, jac=True)``.
    ``tolerance`` sets ``options.tolerance``.

    Each call is one evaluation with its exact gradient from the engines (what ``asnr optimize
    --method gradient`` follows; docs/physics.md, "Gradients"). The keys are checked now, with
    one gradient at the scene's own values (which gives ``f.x0``): an unknown, non-differentiable
    or missing key raises :class:`SceneError` naming it. A key the scene's overrides set
    (``scene.with_({key: v})``) starts at ``v`` and is then set by each call; a key the scene
    lacks (a Binary 2 term past the list's end) may be added that way."""
    scene = _scene(scene)
    if tolerance is not None:
        scene = scene.with_({"options.tolerance": float(tolerance)})
    if objective not in ("asnr", "asnr_glare", "fov_mean"):
        raise SceneError(
            f"objective {objective!r}: the objectives with a gradient are 'asnr', 'asnr_glare' and 'fov_mean' "
            "(worst_channel is a minimum over channels, with no gradient where two tie)"
        )
    text, values = _asnr.gradient(scene, _keys(keys), None, None)
    names = list(json.loads(text)["gradient"])
    _asnr.check_objective(scene, names, objective)  # a key it sets itself, fov_mean without [[fields]]
    return ValueAndGrad(scene, names, np.array(values, dtype=np.float64), objective, float(sign))


def tolerance(
    scene: Scene,
    vary: Mapping[str, str],
    *,
    n: int = 1000,
    seed: int = 1,
    objective: str = "asnr",
    budget_s: float = 600.0,
    threads: int = 0,
) -> dict[str, Any]:
    """How the ASNR survives fabrication: ``asnr tolerance --json`` with one ``--vary KEY=DIST``
    per entry of ``vary`` (``{key: "normal:0.02"}`` in the key's units, ``"normal:2%"`` of its
    value, ``"uniform:LO:HI"``, or ``"seed"``: a fresh whole-number seed each sample, for
    ``lens.atom_error_seed``, a new draw of a library lens's atom errors), ``n`` samples drawn from ``seed`` (the same run as the command
    line's: the same numbers). The dict has the JSON's fields (``nominal_asnr``, ``mean``,
    ``std``, ``p5``, ``p50``, ``p95``, ``keys`` with each key's ``sensitivity_per_sigma``, …),
    ``csv`` (the ``--csv`` text, byte for byte) and ``table`` (its columns as numpy arrays)."""
    pairs = [(str(k), str(v)) for k, v in vary.items()]
    report, csv = _asnr.tolerance(_scene(scene), pairs, int(n), int(seed), objective, float(budget_s), int(threads))
    out = json.loads(report)
    out["csv"] = csv
    lines = csv.splitlines()
    header = lines[0].split(",")
    rows = [line.split(",") for line in lines[1:]]
    table: dict[str, np.ndarray] = {}
    for j, name in enumerate(header):
        column = [r[j] for r in rows]
        if name == "fraunhofer_valid":
            table[name] = np.array([c == "true" for c in column], dtype=bool)
        elif name == "sample":
            table[name] = np.array([int(c) for c in column], dtype=np.int64)
        else:
            table[name] = np.array([float(c) for c in column], dtype=np.float64)
    out["table"] = table
    return out


@dataclasses.dataclass(frozen=True)
class Order:
    """One imaging order of a :class:`LensModel` at one wavelength and field point (SI units,
    the wavefront sign of the README's physics notes: ``defocus_m > 0`` focuses behind the
    detector)."""

    #: fraction of the light on the aperture this order brings to the image, in [0, 1]
    efficiency: float
    #: defocus W020 at the pupil edge, m
    defocus_m: float
    #: lateral displacement (x, y) of the image point on the detector, m (lateral colour)
    image_shift_m: tuple[float, float] = (0.0, 0.0)
    #: Seidel spherical W040, m (any Seidel term sends the order to the FFT path)
    spherical_m: float = 0.0
    #: Seidel coma W131, m
    coma_m: float = 0.0
    #: Seidel astigmatism W222, m
    astigmatism_m: float = 0.0
    #: Seidel field curvature W220, m
    field_curvature_m: float = 0.0
    #: Zernike terms in Noll order from Z1, m RMS (the m = 0 terms keep the radial engine, the
    #: others send the order to the FFT path)
    zernike_noll_m: tuple[float, ...] = ()
    #: any radial polynomial term: OPD = sum c_i rho^(2 i), i = 0, 1, …, m (the radial engine)
    radial_m: tuple[float, ...] = ()


class LensModel:
    """A lens written in Python, for prototyping: subclass it, set ``f_number`` and
    ``focal_length_m`` (and ``design_wavelength_m`` for the Fraunhofer check), and return the
    imaging orders from :meth:`orders`; optionally define ``transmission(wavelength_m)`` (the
    total transmission into all orders, for glare; default: the orders' efficiency). Use it with
    ``scene.with_lens(MyLens())``. The full circular pupil of diameter ``focal_length_m /
    f_number`` is assumed. It is called back from the evaluation under the GIL: a few times
    slower than a lens of the scene file, and an error raised in it is raised by the evaluation."""

    f_number: float
    focal_length_m: float
    design_wavelength_m: float | None = None

    def orders(self, wavelength_m: float, field: tuple[float, float]) -> list[Order]:
        """The imaging orders for light of ``wavelength_m`` from the field angles ``field``
        (x, y in radians)."""
        raise NotImplementedError(f"{type(self).__name__}.orders(wavelength_m, field)")
