//! `asnr._asnr`: the native module of the `asnr` Python package (PyO3).
//!
//! The Python layer (`python/asnr/__init__.py`) gives the user's API (`asnr.load`, `asnr.evaluate`,
//! `asnr.evaluate_many`, `asnr.sweep`, `asnr.mtf`, `asnr.compare`, `asnr.LensModel`); this module
//! does the work with the same functions as the command line, so that a number computed from
//! Python is the number `asnr` prints:
//!
//! - a scene is a [`scene::Source`] (a file's or a text's TOML, parsed once) and its overrides,
//!   `key=value` as `--set` takes them, built by `scene::build_from`;
//! - a point of `evaluate_many` is `scene::sweep::Points::evaluate_with_lens`, the function every
//!   `asnr sweep` point goes through, so its values are the sweep CSV's to the last digit;
//! - reports are the command line's JSON (`metric::Evaluation`, the comparison's `Report`),
//!   decoded in Python;
//! - errors raise `asnr.SceneError` with the command line's message.
//!
//! Long computations release the GIL and run on a rayon pool; `evaluate_many` checks for Ctrl-C
//! between chunks of points. A lens written in Python ([`PyLens`]) is called back under the GIL.

use std::sync::{Arc, Mutex};

// no code: its dependency features let the wheel share the test build's (workspace-hack/Cargo.toml)
use workspace_hack as _;

use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

use optics::{Field, LensModel, Order, Pupil, Wavefront};
use scene::Source;
use scene::sweep::{Point, PointError, Points, assignment};

create_exception!(
    asnr,
    SceneError,
    PyException,
    "A scene that cannot be read, built or evaluated. The message is the command line's: it names the \
     file (or the override), the key, the value and what is accepted."
);

/// The error as Python sees it: the whole chain of causes in one message, as `asnr` prints it.
fn scene_error(e: impl Into<anyhow::Error>) -> PyErr {
    SceneError::new_err(format!("{:#}", e.into()))
}

/// A scene: a scene file's (or a text's) TOML with overrides, and optionally a lens written in
/// Python in place of its `[lens]`.
#[pyclass(frozen, module = "asnr._asnr")]
#[derive(Clone)]
struct Scene {
    source: Source,
    overrides: Vec<String>,
    lens: Option<Arc<PyLens>>,
}

impl Scene {
    /// The validated scene.
    fn build(&self) -> Result<metric::Scene, scene::Error> {
        let built = scene::build_from(&self.source, &self.overrides)?;
        Ok(match &self.lens {
            Some(lens) => built.with_lens(lens.clone()),
            None => built,
        })
    }

    /// This scene without the lens keys `keys` (`lens.KEY`), in its file and in its overrides:
    /// the design that `with_phase_map` or `with_layout` gives anew.
    fn without_lens_keys(&self, keys: &[&str]) -> Scene {
        let source = self.source.without_lens_keys(keys);
        let overrides = self
            .overrides
            .iter()
            .filter(|o| {
                let key = o.split('=').next().unwrap_or_default().trim();
                let key = key.strip_prefix("lens.").unwrap_or_default();
                let base = key.split('[').next().unwrap_or_default();
                !keys.contains(&base)
            })
            .cloned()
            .collect();
        Scene { source, overrides, lens: self.lens.clone() }
    }

    /// Refuses lens keys when the lens is Python's: they would not reach it.
    fn check_keys<'a>(&self, keys: impl IntoIterator<Item = &'a str>) -> PyResult<()> {
        if let Some(lens) = &self.lens {
            for key in keys {
                // the relative illumination is the scene's (every family's), not the lens model's
                if key.starts_with("lens.") && key != "lens.relative_illumination" {
                    return Err(SceneError::new_err(format!(
                        "{}: {key}: the scene's lens is the Python object {}; its keys are set in Python, not as scene keys",
                        self.source.label(),
                        lens.name
                    )));
                }
            }
        }
        Ok(())
    }
}

/// The lens keys that give a phase lens's phase: `Scene.with_phase_map` gives the phase anew and
/// leaves them out (the keys a map is refused with, and an earlier map's).
const PHASE_DESIGN_KEYS: [&str; 9] = [
    "binary2",
    "norm_radius_mm",
    "diffraction_order",
    "phase_csv",
    "phase_spline_rad",
    "phase_map",
    "amplitude_map",
    "zemax",
    "zemax_surface",
];

/// The lens keys that give a library lens's layout: `Scene.with_layout` gives the layout anew and
/// leaves them out.
const LAYOUT_KEYS: [&str; 8] =
    ["layout", "layout_grid", "layout_gds", "gds_cell", "gds_layer", "gds_datatype", "atom", "handedness"];

/// `scene` with the numpy array `value` for `key` (one of [`scene::ARRAY_KEYS`]) in place of a
/// `.npy` file: its values copied once (float32 or float64, any memory order, read in C order as
/// a `.npy` file is), the key set to a text naming the array (`<numpy float64 array 512 × 512>`),
/// which messages and `to_toml` show. A layout grid's leading parameter axis of one is dropped.
fn with_array(mut scene: Scene, key: &str, value: &Bound<'_, PyAny>) -> PyResult<Scene> {
    let (dtype, mut shape, values): (&str, Vec<u64>, Vec<f64>) =
        if let Ok(a) = value.extract::<numpy::PyReadonlyArrayDyn<'_, f64>>() {
            let a = a.as_array();
            ("float64", a.shape().iter().map(|&n| n as u64).collect(), a.iter().copied().collect())
        } else if let Ok(a) = value.extract::<numpy::PyReadonlyArrayDyn<'_, f32>>() {
            let a = a.as_array();
            ("float32", a.shape().iter().map(|&n| n as u64).collect(), a.iter().map(|&v| f64::from(v)).collect())
        } else {
            return Err(PyTypeError::new_err(format!(
                "{key}: a {}: expected a numpy float array (float32 or float64) [y, x], or the path of a .npy file",
                value.get_type().name()?
            )));
        };
    if key == "lens.layout_grid" && shape.len() == 3 && shape[0] == 1 {
        shape.remove(0);
    }
    let label =
        format!("<numpy {dtype} array {}>", shape.iter().map(ToString::to_string).collect::<Vec<_>>().join(" × "));
    scene.source = scene.source.with_array(key, label.clone(), shape, values).map_err(SceneError::new_err)?;
    replace_override(&mut scene.overrides, key, format!("{key}={}", toml::Value::String(label)));
    Ok(scene)
}

/// `overrides` with `text` (`key=value`) in place of any earlier override of `key`: a value given
/// anew by `with_phase_map`, `with_layout` or an array (an override may name a key once).
fn replace_override(overrides: &mut Vec<String>, key: &str, text: String) {
    overrides.retain(|o| o.split('=').next().unwrap_or_default().trim() != key);
    overrides.push(text);
}

/// `key=value` for an override given in Python: numbers as `asnr sweep` writes them (the shortest
/// decimal that reads back to the same float), integers and booleans as TOML's, strings quoted.
fn override_text(key: &str, value: &Bound<'_, PyAny>) -> PyResult<String> {
    if value.is_instance_of::<PyBool>() {
        Ok(format!("{key}={}", value.extract::<bool>()?))
    } else if value.is_instance_of::<PyInt>() {
        Ok(format!("{key}={}", value.extract::<i64>()?))
    } else if value.is_instance_of::<PyFloat>() || value.hasattr("__float__")? && !value.is_instance_of::<PyString>() {
        Ok(assignment(key, value.extract::<f64>()?))
    } else if let Ok(text) = value.cast::<PyString>() {
        Ok(format!("{key}={}", toml::Value::String(text.to_str()?.to_owned())))
    } else {
        Err(PyTypeError::new_err(format!(
            "{key}: a {}: expected a number, a bool or a string",
            value.get_type().name()?
        )))
    }
}

/// Overrides given in Python: a dict is written as `Scene.with_` writes it; a list holds
/// `key=value` strings as typed (`--set`'s).
fn override_list(overrides: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<String>> {
    Ok(match overrides {
        None => Vec::new(),
        Some(o) => match o.cast::<PyDict>() {
            Ok(dict) => {
                dict.iter().map(|(k, v)| override_text(&k.extract::<String>()?, &v)).collect::<PyResult<_>>()?
            }
            Err(_) => o.extract()?,
        },
    })
}

#[pymethods]
impl Scene {
    /// How messages name the scene (its file, or "embedded paper scene").
    #[getter]
    fn label(&self) -> String {
        self.source.label().to_owned()
    }

    /// The overrides applied to the file, `key=value` as `asnr --set` takes them.
    #[getter]
    fn overrides(&self) -> Vec<String> {
        self.overrides.clone()
    }

    /// This scene with more overrides (a dict of dotted keys to values), validated now. The keys
    /// that name a `.npy` map (`lens.phase_map`, `lens.amplitude_map`, `lens.layout_grid`) also
    /// take a numpy array (see [`with_array`]).
    fn with_(&self, overrides: &Bound<'_, PyDict>) -> PyResult<Scene> {
        let mut next = self.clone();
        for (key, value) in overrides.iter() {
            let key: String = key.extract()?;
            self.check_keys([key.as_str()])?;
            if scene::ARRAY_KEYS.contains(&key.as_str()) && !value.is_instance_of::<PyString>() {
                next = with_array(next, &key, &value)?;
            } else {
                next.overrides.push(override_text(&key, &value)?);
            }
        }
        next.build().map_err(scene_error)?;
        Ok(next)
    }

    /// This scene's lens as the 2-D phase map `phase` (radians at the design wavelength, `[y, x]`,
    /// a numpy float array) with cells of `pitch_um`, and optionally the map `amplitude` of the
    /// same shape, the `aperture` ("circle" or "square") and the `dispersion` ("geometric-phase",
    /// "diffractive", "refractive"; a scene whose lens is not a phase lens has none), each given
    /// as `lens.KEY`: `lens.model = "phase"` with the keys
    /// a scene file gives as `.npy` files, checked as theirs are. The phase given anew replaces
    /// the lens's own: its [`PHASE_DESIGN_KEYS`] are left out; every other lens key is kept.
    #[pyo3(signature = (phase, *, pitch_um, amplitude=None, aperture=None, dispersion=None))]
    fn with_phase_map(
        &self,
        phase: &Bound<'_, PyAny>,
        pitch_um: &Bound<'_, PyAny>,
        amplitude: Option<&Bound<'_, PyAny>>,
        aperture: Option<&Bound<'_, PyAny>>,
        dispersion: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Scene> {
        self.check_keys(["lens.phase_map"])?;
        let mut next = self.without_lens_keys(&PHASE_DESIGN_KEYS);
        next = with_array(next, "lens.phase_map", phase)?;
        if let Some(amplitude) = amplitude {
            next = with_array(next, "lens.amplitude_map", amplitude)?;
        }
        replace_override(&mut next.overrides, "lens.model", "lens.model=\"phase\"".to_owned());
        replace_override(
            &mut next.overrides,
            "lens.phase_map_pitch_um",
            override_text("lens.phase_map_pitch_um", pitch_um)?,
        );
        if let Some(aperture) = aperture {
            replace_override(&mut next.overrides, "lens.aperture", override_text("lens.aperture", aperture)?);
        }
        if let Some(dispersion) = dispersion {
            replace_override(&mut next.overrides, "lens.dispersion", override_text("lens.dispersion", dispersion)?);
        }
        next.build().map_err(scene_error)?;
        Ok(next)
    }

    /// This scene's lens as the library lens laid out on the square lattice `grid` (the library's
    /// one parameter per site, `[y, x]` or `[1, y, x]`, NaN where a site has no atom; a numpy float
    /// array) of `pitch_um`: `lens.model = "library"` with `lens.layout_grid`, checked as a `.npy`
    /// grid is. The layout given anew replaces the lens's own: its [`LAYOUT_KEYS`] are left out;
    /// every other lens key is kept.
    #[pyo3(signature = (grid, *, pitch_um))]
    fn with_layout(&self, grid: &Bound<'_, PyAny>, pitch_um: &Bound<'_, PyAny>) -> PyResult<Scene> {
        self.check_keys(["lens.layout_grid"])?;
        let mut next = self.without_lens_keys(&LAYOUT_KEYS);
        next = with_array(next, "lens.layout_grid", grid)?;
        replace_override(&mut next.overrides, "lens.model", "lens.model=\"library\"".to_owned());
        replace_override(
            &mut next.overrides,
            "lens.lattice_pitch_um",
            override_text("lens.lattice_pitch_um", pitch_um)?,
        );
        next.build().map_err(scene_error)?;
        Ok(next)
    }

    /// This scene with a lens written in Python (an object with `f_number`, `focal_length_m` and
    /// `orders(wavelength_m, field)`): see `asnr.LensModel`.
    fn with_lens(&self, lens: &Bound<'_, PyAny>) -> PyResult<Scene> {
        let lens = PyLens::new(lens)?;
        let mut next = Scene { lens: Some(Arc::new(lens)), ..self.clone() };
        // the file's lens keys no longer apply, but the overrides of the others still do
        next.overrides.retain(|o| {
            let o = o.trim_start();
            !o.starts_with("lens.") || o.starts_with("lens.relative_illumination=")
        });
        next.build().map_err(scene_error)?;
        Ok(next)
    }

    /// The scene as read, with every default filled in (`asnr scene`), as TOML text.
    fn to_toml(&self) -> PyResult<String> {
        Ok(scene::resolved_toml(&self.source, &self.overrides).map_err(scene_error)?.toml)
    }

    /// Pickling (Dask and multiprocessing send scenes to workers): the scene's text, label,
    /// folder and overrides, the Python lens object if it has one, and the arrays it was given
    /// in memory (each key, its text, shape and values).
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let rebuild = py.import("asnr._asnr")?.getattr("_rebuild_scene")?;
        let lens = self.lens.as_ref().map(|l| l.object.clone_ref(py));
        let arrays: Vec<PickledArray<Bound<'py, PyArray1<f64>>>> = self
            .source
            .arrays()
            .map(|(key, label, shape, values)| {
                (key.to_owned(), label.to_owned(), shape.to_vec(), PyArray1::from_slice(py, values))
            })
            .collect();
        let args = (
            self.source.text(),
            self.source.label(),
            self.source.dir().to_path_buf(),
            self.overrides.clone(),
            lens,
            arrays,
        )
            .into_pyobject(py)?;
        Ok((rebuild, args))
    }

    fn __repr__(&self) -> String {
        let lens = self.lens.as_ref().map_or(String::new(), |l| format!(", lens={}", l.name));
        format!("Scene({:?}, overrides={:?}{lens})", self.source.label(), self.overrides)
    }
}

/// The scene file `path` (None: the embedded paper scene).
#[pyfunction]
#[pyo3(signature = (path=None))]
fn load_file(path: Option<std::path::PathBuf>) -> PyResult<Scene> {
    let source = scene::read(path.as_deref()).map_err(scene_error)?;
    let scene = Scene { source, overrides: Vec::new(), lens: None };
    scene.build().map_err(scene_error)?;
    Ok(scene)
}

/// A scene given as TOML text; CSV paths resolve against `directory`.
#[pyfunction]
fn load_text(text: String, label: String, directory: std::path::PathBuf) -> PyResult<Scene> {
    let scene = Scene { source: Source::from_text(text, label, directory), overrides: Vec::new(), lens: None };
    scene.build().map_err(scene_error)?;
    Ok(scene)
}

/// A scene given as JSON text (a Python dict dumped), turned into TOML; CSV paths resolve
/// against `directory`.
#[pyfunction]
fn load_json(json: &str, label: String, directory: std::path::PathBuf) -> PyResult<Scene> {
    let value: serde_json::Value = serde_json::from_str(json).map_err(|e| PyValueError::new_err(e.to_string()))?;
    let table: toml::Table = toml::Table::try_from(value).map_err(|e| {
        SceneError::new_err(format!("{label}: cannot be written as TOML: {e} (None values are not allowed)"))
    })?;
    load_text(table.to_string(), label, directory)
}

/// An array given in memory, as a pickle holds it: its key, its text, its shape and its values.
type PickledArray<A> = (String, String, Vec<u64>, A);

/// The scene [`Scene::__reduce__`] pickled.
#[pyfunction]
#[pyo3(signature = (text, label, directory, overrides, lens, arrays=None))]
fn _rebuild_scene(
    text: String,
    label: String,
    directory: std::path::PathBuf,
    overrides: Vec<String>,
    lens: Option<Bound<'_, PyAny>>,
    arrays: Option<Vec<PickledArray<PyReadonlyArray1<'_, f64>>>>,
) -> PyResult<Scene> {
    let lens = lens.map(|l| PyLens::new(&l).map(Arc::new)).transpose()?;
    let mut source = Source::from_text(text, label, directory);
    for (key, label, shape, values) in arrays.unwrap_or_default() {
        source = source.with_array(&key, label, shape, values.as_array().to_vec()).map_err(SceneError::new_err)?;
    }
    Ok(Scene { source, overrides, lens })
}

/// The evaluation of a scene (`asnr evaluate --json`'s `result`, as JSON text) and the scene's
/// plausibility warnings. The GIL is released while it runs.
///
/// With `metrics` (`(object, contrast, frame_rate_hz, task)` in `asnr evaluate --metrics`'s
/// words, each optional) the report also holds the metrics' fields, as `--metrics --json` prints
/// them (`report::metrics::json`).
#[pyfunction]
#[pyo3(signature = (scene, metrics=None))]
fn evaluate(py: Python<'_>, scene: &Scene, metrics: Option<MetricsWords>) -> PyResult<(String, String, Vec<String>)> {
    let metrics_options = metrics
        .map(|(object, contrast, frame_rate_hz, task)| {
            report::metrics::options(object.as_deref(), contrast, frame_rate_hz, task.as_deref())
        })
        .transpose()
        .map_err(scene_error)?;
    let loaded = scene::build_with_warnings(&scene.source, &scene.overrides).map_err(scene_error)?;
    let warnings = loaded.warnings.iter().map(ToString::to_string).collect();
    let built = match &scene.lens {
        Some(lens) => loaded.scene.with_lens(lens.clone()),
        None => loaded.scene,
    };
    let result = py.detach(|| metric::evaluate(&built));
    if let Some(lens) = &scene.lens {
        lens.raise()?;
    }
    let result = result.map_err(|e| SceneError::new_err(format!("{}: {e}", scene.source.label())))?;
    let report = match metrics_options {
        None => report::output::json(scene.source.label(), &built, &result).map_err(scene_error)?,
        Some(options) => {
            let m = py.detach(|| metric::metrics(&built, &result, &options));
            if let Some(lens) = &scene.lens {
                lens.raise()?;
            }
            let m = m.map_err(|e| SceneError::new_err(format!("{}: {e}", scene.source.label())))?;
            report::metrics::json(scene.source.label(), &built, &result, &m).map_err(scene_error)?
        }
    };
    Ok((report, built.lens().describe(), warnings))
}

/// The words of `asnr evaluate --metrics`: `--object`, `--contrast`, `--frame-rate-hz`, `--task`.
type MetricsWords = (Option<String>, Option<f64>, Option<f64>, Option<String>);

/// A frame given from Python: a path (a file, a folder or a pattern, as the command line takes
/// them), or `(name, 2-D float64 array, bits)` where bits is the camera's 8 or 16 (unsigned
/// integers: the largest code is the clip level) or 32 (floating point).
#[derive(FromPyObject)]
enum FrameInput<'py> {
    Path(std::path::PathBuf),
    Array(String, numpy::PyReadonlyArray2<'py, f64>, u8),
}

/// A bad measurement input: the command line's message (the file or array, the reason).
fn input_error(e: impl Into<anyhow::Error>) -> PyErr {
    PyValueError::new_err(format!("{:#}", e.into()))
}

/// The frames `inputs` name or hold, in order, one size and bit depth; `what` names them in
/// messages. Memory stays bounded as the command line's: at most
/// `imaging::frames::MAX_STACK_SAMPLES` grey levels in all.
fn frames_from(what: &'static str, inputs: &[FrameInput<'_>]) -> PyResult<Vec<imaging::Frame>> {
    let mut frames: Vec<imaging::Frame> = Vec::new();
    let mut samples = 0_u64;
    for (i, input) in inputs.iter().enumerate() {
        let read = match input {
            FrameInput::Path(path) => {
                imaging::frames::read_frames(what, std::slice::from_ref(path), 1).map_err(input_error)?
            }
            FrameInput::Array(name, array, bits) => {
                let (height, width) = array.as_array().dim();
                if width == 0 || height == 0 || (width * height) as u64 > imaging::frames::MAX_FRAME_PIXELS {
                    return Err(PyValueError::new_err(format!(
                        "{what}[{i}] ({name}): {width} × {height} pixels: expected 1 to {} pixels",
                        imaging::frames::MAX_FRAME_PIXELS
                    )));
                }
                if ![8, 16, 32].contains(bits) {
                    return Err(PyValueError::new_err(format!(
                        "{what}[{i}] ({name}): {bits} bits: expected 8 or 16 (unsigned integers) or 32 (floating point)"
                    )));
                }
                let data: Vec<f64> = array.as_array().iter().copied().collect();
                if let Some(k) = data.iter().position(|v| !v.is_finite()) {
                    return Err(PyValueError::new_err(format!(
                        "{what}[{i}] ({name}): {} at row {}, column {}: expected finite grey levels",
                        data[k],
                        k / width,
                        k % width
                    )));
                }
                vec![imaging::Frame { path: name.into(), width, height, bit_depth: *bits, data }]
            }
        };
        for frame in read {
            if let Some(first) = frames.first() {
                imaging::frames::same_format(first, &frame).map_err(input_error)?;
            }
            samples += (frame.width * frame.height) as u64;
            if samples > imaging::frames::MAX_STACK_SAMPLES {
                return Err(PyValueError::new_err(format!(
                    "{what}: more than the {} grey levels a stack may hold (at {})",
                    imaging::frames::MAX_STACK_SAMPLES,
                    frame.path.display()
                )));
            }
            frames.push(frame);
        }
    }
    Ok(frames)
}

/// `asnr sfr --json` of the frames `images` (and `dark`), as JSON text: the same options, the
/// same analysis (`imaging::sfr`), the same object (`report::measure::sfr_json`). The GIL is
/// released while it runs.
#[pyfunction]
#[pyo3(signature = (images, roi=None, dark=Vec::new(), gamma=None, transfer=None, pixel_pitch_um=None, curved=false, reach=None))]
#[allow(clippy::too_many_arguments)] // Python's keyword arguments, each one of `asnr sfr`'s options
fn sfr(
    py: Python<'_>,
    images: Vec<FrameInput<'_>>,
    roi: Option<String>,
    dark: Vec<FrameInput<'_>>,
    gamma: Option<f64>,
    transfer: Option<std::path::PathBuf>,
    pixel_pitch_um: Option<f64>,
    curved: bool,
    reach: Option<f64>,
) -> PyResult<String> {
    let options =
        report::measure::sfr_options(roi.as_deref(), gamma, transfer.as_deref(), pixel_pitch_um, curved, reach)
            .map_err(input_error)?;
    if images.is_empty() {
        return Err(PyValueError::new_err("sfr: no images; expected one or more frames of the edge"));
    }
    let frames = frames_from("images", &images)?;
    let dark = frames_from("dark", &dark)?;
    let result = py.detach(|| imaging::sfr(&frames, &dark, &options)).map_err(input_error)?;
    let value = report::measure::sfr_json(&result).map_err(input_error)?;
    serde_json::to_string(&value).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// `asnr measure --json` of the stack `frames`, as JSON text: the same computation
/// (`report::measure::measure`). `compare` is a scene evaluated with `camera.pixel_mtf = true`
/// (a measured edge contains the pixel aperture), as `--compare` does.
#[pyfunction]
#[pyo3(signature = (frames, white, black, capped_black=Vec::new(), include_glare=false, edge=Vec::new(), edge_roi=None, mtf_csv=None, pixel_pitch_um=None, compare=None))]
#[allow(clippy::too_many_arguments)] // Python's keyword arguments, each one of `asnr measure`'s options
fn measure(
    py: Python<'_>,
    frames: Vec<FrameInput<'_>>,
    white: String,
    black: String,
    capped_black: Vec<FrameInput<'_>>,
    include_glare: bool,
    edge: Vec<FrameInput<'_>>,
    edge_roi: Option<String>,
    mtf_csv: Option<std::path::PathBuf>,
    pixel_pitch_um: Option<f64>,
    compare: Option<&Scene>,
) -> PyResult<String> {
    let white = imaging::Region::parse("white", &white).map_err(input_error)?;
    let black = imaging::Region::parse("black", &black).map_err(input_error)?;
    if !edge.is_empty() && mtf_csv.is_some() {
        return Err(PyValueError::new_err("measure: an edge and an MTF table: give one of edge and mtf_csv"));
    }
    if edge_roi.is_some() && edge.is_empty() {
        return Err(PyValueError::new_err("measure: edge_roi without edge frames: give edge too"));
    }
    let frames = frames_from("frames", &frames)?;
    if frames.len() < 2 {
        return Err(input_error(imaging::Error::TooFewFrames { what: "frames", frames: frames.len() }));
    }
    let capped = if capped_black.is_empty() { None } else { Some(frames_from("capped_black", &capped_black)?) };
    let edge = if edge.is_empty() { None } else { Some(frames_from("edge", &edge)?) };
    let simulated = match compare {
        None => None,
        Some(scene) => {
            let mut with_pixel = scene.clone();
            with_pixel.overrides.push("camera.pixel_mtf=true".to_owned());
            Some((scene.source.label().to_owned(), with_pixel.build().map_err(scene_error)?))
        }
    };
    let mtf = match (&edge, &mtf_csv) {
        (Some(frames), _) => Some(report::measure::MtfFrom::Edge { frames, roi: edge_roi.as_deref() }),
        (None, Some(path)) => Some(report::measure::MtfFrom::Table(path)),
        (None, None) => None,
    };
    let inputs = report::measure::MeasureInputs {
        white,
        black,
        capped: capped.as_deref(),
        include_glare,
        mtf,
        pixel_pitch_um,
        compare: simulated.as_ref().map(|(label, scene)| (label.as_str(), scene)),
    };
    let report = py.detach(|| report::measure::measure(&frames, &inputs));
    if let Some(lens) = compare.and_then(|s| s.lens.as_ref()) {
        lens.raise()?;
    }
    let report = report.map_err(input_error)?;
    serde_json::to_string(&report.json().map_err(input_error)?).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// The ASNR at many points: `columns[k][i]` is key `keys[k]` at point `i`. Returns a dict of
/// numpy arrays (`mean_mtf`, `snr0`, `asnr`, `photoelectrons`, `fraunhofer_valid`) and the list
/// `warnings` (each point's, joined by " | "). Points run on `threads` threads (0: all cores) in
/// chunks of `chunk`, the GIL released; Ctrl-C is honoured between chunks.
#[pyfunction]
#[pyo3(signature = (scene, keys, columns, threads=0, chunk=256))]
fn evaluate_many<'py>(
    py: Python<'py>,
    scene: &Scene,
    keys: Vec<String>,
    columns: Vec<PyReadonlyArray1<'py, f64>>,
    threads: usize,
    chunk: usize,
) -> PyResult<Bound<'py, PyDict>> {
    use rayon::prelude::*;
    if keys.len() != columns.len() {
        return Err(PyValueError::new_err(format!("{} keys but {} columns", keys.len(), columns.len())));
    }
    scene.check_keys(keys.iter().map(String::as_str))?;
    let columns: Vec<Vec<f64>> = columns
        .iter()
        .map(|c| c.as_slice().map(<[f64]>::to_vec))
        .collect::<Result<_, _>>()
        .map_err(|e| PyValueError::new_err(format!("the values must be contiguous float64 arrays: {e}")))?;
    let n = columns.first().map_or(1, Vec::len);
    if let Some((k, c)) = keys.iter().zip(&columns).find(|(_, c)| c.len() != n) {
        return Err(PyValueError::new_err(format!(
            "{k}: {} values; expected {n}, as many as the first key's",
            c.len()
        )));
    }
    if let Some((k, v)) = keys.iter().zip(&columns).find_map(|(k, c)| c.iter().find(|v| !v.is_finite()).map(|v| (k, v)))
    {
        return Err(SceneError::new_err(format!("{}: {k} = {v}: expected finite numbers", scene.source.label())));
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| PyValueError::new_err(format!("threads = {threads}: {e}")))?;
    let chunk = chunk.max(1);
    // the scene's text parsed and merged once for every point (`scene::sweep::Points`, as a sweep)
    let prepared = Points::new(&scene.source, &scene.overrides, &keys);
    let mut points: Vec<Point> = Vec::with_capacity(n);
    let mut start = 0;
    while start < n {
        let end = (start + chunk).min(n);
        let results: Vec<Result<Point, PointError>> = py.detach(|| {
            pool.install(|| {
                (start..end)
                    .into_par_iter()
                    .map(|i| {
                        let values: Vec<f64> = columns.iter().map(|c| c[i]).collect();
                        let lens = scene.lens.clone().map(|l| l as Arc<dyn LensModel>);
                        prepared.evaluate_with_lens(&values, lens)
                    })
                    .collect()
            })
        });
        if let Some(lens) = &scene.lens {
            lens.raise()?;
        }
        for (i, r) in (start..end).zip(results) {
            let point = r.map_err(|e| {
                let at: Vec<String> = keys.iter().zip(&columns).map(|(k, c)| format!("{k}={}", c[i])).collect();
                scene_error(anyhow::Error::new(e).context(format!("at point {i} ({})", at.join(", "))))
            })?;
            points.push(point);
        }
        py.check_signals()?;
        start = end;
    }
    let out = PyDict::new(py);
    let column = |f: fn(&Point) -> f64| PyArray1::from_vec(py, points.iter().map(f).collect());
    out.set_item("mean_mtf", column(|p| p.mean_mtf))?;
    out.set_item("snr0", column(|p| p.snr0))?;
    out.set_item("asnr", column(|p| p.asnr))?;
    out.set_item("photoelectrons", column(|p| p.photoelectrons))?;
    out.set_item("fraunhofer_valid", PyArray1::from_vec(py, points.iter().map(|p| p.fraunhofer_valid).collect()))?;
    out.set_item("warnings", PyList::new(py, points.iter().map(|p| p.warnings.join(" | ")))?)?;
    Ok(out)
}

/// `n` values from `lo` to `hi`, both included, equally spaced, as `asnr sweep --over KEY=LO:HI:N`
/// makes them (the same floats).
#[pyfunction]
fn axis<'py>(py: Python<'py>, lo: f64, hi: f64, n: usize) -> PyResult<Bound<'py, PyArray1<f64>>> {
    if !(lo.is_finite() && hi.is_finite() && lo < hi) || n == 0 {
        return Err(PyValueError::new_err(format!("axis({lo}, {hi}, {n}): expected finite lo < hi and n ≥ 1")));
    }
    Ok(PyArray1::from_vec(py, scene::sweep::axis(lo, hi, n)))
}

/// One row for [`sweep_csv`]: the point's values, mean MTF, SNR0, ASNR, photoelectrons, Fraunhofer
/// validity and its warnings joined by " | ".
type CsvRow = (Vec<f64>, f64, f64, f64, f64, bool, String);

/// The CSV `asnr sweep --csv` writes for these points (`keys` and each point's values as
/// `evaluate_many` got them, its results as it returned them).
#[pyfunction]
fn sweep_csv(keys: Vec<String>, rows: Vec<CsvRow>) -> String {
    let mut s = scene::sweep::csv_header(&keys, false);
    for (values, mean_mtf, snr0, asnr, photoelectrons, fraunhofer_valid, warnings) in rows {
        let warnings = if warnings.is_empty() { Vec::new() } else { vec![warnings] };
        let point = Point { values, mean_mtf, snr0, asnr, photoelectrons, fraunhofer_valid, warnings };
        s.push_str(&scene::sweep::csv_row(&point, None));
    }
    s
}

/// The polychromatic MTF at the frequencies `frequencies` (cycles/mm), with the diffraction limit
/// and the monochromatic MTFs at `wavelengths_nm`: `metric::mtf_at`'s curves as JSON text.
#[pyfunction]
#[pyo3(signature = (scene, frequencies, wavelengths_nm=Vec::new()))]
fn mtf(
    py: Python<'_>,
    scene: &Scene,
    frequencies: PyReadonlyArray1<'_, f64>,
    wavelengths_nm: Vec<f64>,
) -> PyResult<String> {
    let frequencies = frequencies
        .as_slice()
        .map_err(|e| PyValueError::new_err(format!("the frequencies must be a contiguous float64 array: {e}")))?
        .to_vec();
    if let Some(bad) = wavelengths_nm.iter().find(|w| !(w.is_finite() && **w > 0.0)) {
        return Err(PyValueError::new_err(format!("wavelengths_nm: {bad} nm: expected wavelengths > 0 nm")));
    }
    let built = scene.build().map_err(scene_error)?;
    let metres: Vec<f64> = wavelengths_nm.iter().map(|w| w * 1e-9).collect();
    let curve = py.detach(|| metric::mtf_at(&built, &frequencies, &metres));
    if let Some(lens) = &scene.lens {
        lens.raise()?;
    }
    let curve = curve.map_err(|e| SceneError::new_err(format!("{}: {e}", scene.source.label())))?;
    serde_json::to_string(&curve).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// `asnr compare`'s report as JSON text, and the comparison's plausibility warnings: the comparison file `path` (None: the embedded
/// comparison of the lens families) with `overrides` (a dict of keys to values, or `key=value`
/// strings), the best band searched over `over`.
#[pyfunction]
#[pyo3(signature = (path=None, overrides=None, tolerance=None, over=None, threads=0))]
fn compare(
    py: Python<'_>,
    path: Option<std::path::PathBuf>,
    overrides: Option<&Bound<'_, PyAny>>,
    tolerance: Option<f64>,
    over: Option<String>,
    threads: usize,
) -> PyResult<(String, Vec<String>)> {
    let overrides = override_list(overrides)?;
    let (base, report) = py
        .detach(|| report::compare::compare(path.as_deref(), &overrides, tolerance, over.as_deref(), threads, &()))
        .map_err(scene_error)?;
    let warnings = base.warnings.iter().map(ToString::to_string).collect();
    Ok((serde_json::to_string(&report).map_err(|e| PyValueError::new_err(e.to_string()))?, warnings))
}

/// Refuses a scene whose lens is a Python object for a design search (its keys are not scene keys).
fn scene_lens_only(scene: &Scene, what: &str) -> PyResult<()> {
    match &scene.lens {
        Some(lens) => Err(SceneError::new_err(format!(
            "{what}: the scene's lens is the Python object {}; a design search varies scene keys, so it needs the scene file's lens",
            lens.name
        ))),
        None => Ok(()),
    }
}

/// `asnr optimize --json` for `scene` over `over` (`(key, lo, hi)` each, as `--over KEY=LO:HI`)
/// by `method` (`--method cobyla|gradient`; None: as without the flag): the same search
/// (`report::optimize::search_scene_by`), so the same numbers. The GIL is released while it
/// runs.
#[pyfunction]
#[pyo3(signature = (scene, over, objective="asnr", xtol=1e-4, starts=0, max_evaluations=500, method=None))]
#[allow(clippy::too_many_arguments)] // Python's keyword arguments, each one of `asnr optimize`'s options
fn optimize(
    py: Python<'_>,
    scene: &Scene,
    over: Vec<(String, f64, f64)>,
    objective: &str,
    xtol: f64,
    starts: usize,
    max_evaluations: usize,
    method: Option<&str>,
) -> PyResult<String> {
    scene_lens_only(scene, "optimize")?;
    let ranges = over
        .iter()
        .map(|(k, lo, hi)| report::optimize::parse_range(&format!("{k}={lo}:{hi}"), false))
        .collect::<anyhow::Result<Vec<_>>>()
        .map_err(scene_error)?;
    let objective = report::objective::Objective::parse(objective).map_err(scene_error)?;
    let method = method.map(report::optimize::Method::parse).transpose().map_err(scene_error)?;
    let search = report::optimize::Search { xtol, starts, max_evaluations };
    let outcome = py
        .detach(|| {
            report::optimize::search_scene_by(
                scene.source.clone(),
                scene.overrides.clone(),
                &ranges,
                objective,
                &search,
                method,
                &(),
            )
        })
        .map_err(scene_error)?;
    report::optimize::outcome_json(&outcome).map_err(scene_error)
}

/// `asnr gradient --json` for `scene` with the further `overrides` (a dict, or `key=value`
/// strings as `--set` takes them) and `tolerance` (`--tolerance`: `options.tolerance`), with
/// respect to `keys` (`--wrt`): the same function (`report::gradient::gradient`), so the same
/// JSON text, and the keys' values in the scene (in the JSON's order of keys). The GIL is
/// released while it runs.
#[pyfunction]
#[pyo3(signature = (scene, keys, overrides=None, tolerance=None))]
fn gradient(
    py: Python<'_>,
    scene: &Scene,
    keys: Vec<String>,
    overrides: Option<&Bound<'_, PyAny>>,
    tolerance: Option<f64>,
) -> PyResult<(String, Vec<f64>)> {
    scene_lens_only(scene, "gradient")?;
    let mut set = scene.overrides.clone();
    set.extend(override_list(overrides)?);
    if let Some(t) = tolerance {
        set.push(format!("options.tolerance={t}"));
    }
    let g = py.detach(|| report::gradient::gradient(&scene.source, &set, &keys)).map_err(scene_error)?;
    Ok((serde_json::to_string_pretty(&g).map_err(|e| PyValueError::new_err(e.to_string()))?, g.values))
}

/// The design target of `asnr optimize` for `scene` (`objective`, varying `keys`), checked. An
/// override of the scene that sets one of the keys (`scene.with_({key: x0})`, the point a search
/// starts from) is left out: the key's value is the one each call gives.
fn target(scene: &Scene, objective: &str, keys: &[String]) -> PyResult<report::objective::Target> {
    scene_lens_only(scene, "value_and_grad")?;
    let objective = report::objective::Objective::parse(objective).map_err(scene_error)?;
    let overrides: Vec<String> = scene
        .overrides
        .iter()
        .filter(|o| o.split_once('=').is_none_or(|(k, _)| !keys.iter().any(|key| key == k.trim())))
        .cloned()
        .collect();
    report::objective::Target::new(scene.source.clone(), overrides, objective, keys).map_err(scene_error)
}

/// Checks the design target of `scene` (`objective`, varying `keys`) without evaluating it: the
/// objective's name, the keys it sets itself, `[[fields]]` for `fov_mean`.
#[pyfunction]
fn check_objective(scene: &Scene, keys: Vec<String>, objective: &str) -> PyResult<()> {
    target(scene, objective, &keys).map(|_| ())
}

/// The values of the keys, checked: as many as the keys, finite.
fn key_values(keys: &[String], values: &PyReadonlyArray1<'_, f64>) -> PyResult<Vec<f64>> {
    let values = values
        .as_slice()
        .map_err(|e| PyValueError::new_err(format!("the values must be a contiguous float64 array: {e}")))?
        .to_vec();
    if values.len() != keys.len() {
        return Err(PyValueError::new_err(format!(
            "{} values for the {} keys {}: expected one value per key",
            values.len(),
            keys.len(),
            keys.join(", ")
        )));
    }
    if let Some((k, v)) = keys.iter().zip(&values).find(|(_, v)| !v.is_finite()) {
        return Err(PyValueError::new_err(format!("{k} = {v}: expected a finite number")));
    }
    Ok(values)
}

/// The objective (`asnr optimize --objective`'s) of `scene` with `keys[i] = values[i]`
/// (`report::objective::Target::value`, what `asnr optimize` evaluates). The GIL is released.
#[pyfunction]
#[pyo3(signature = (scene, keys, values, objective="asnr"))]
fn objective_value(
    py: Python<'_>,
    scene: &Scene,
    keys: Vec<String>,
    values: PyReadonlyArray1<'_, f64>,
    objective: &str,
) -> PyResult<f64> {
    let target = target(scene, objective, &keys)?;
    let values = key_values(&keys, &values)?;
    Ok(py.detach(|| target.value(&keys, &values)).map_err(scene_error)?.value)
}

/// The objective of `scene` with `keys[i] = values[i]` and its gradient with respect to the
/// keys, each in its own units (`report::objective::Target::value_and_gradient`, what
/// `asnr optimize --method gradient` follows). The GIL is released.
#[pyfunction]
#[pyo3(signature = (scene, keys, values, objective="asnr"))]
fn objective_value_and_gradient<'py>(
    py: Python<'py>,
    scene: &Scene,
    keys: Vec<String>,
    values: PyReadonlyArray1<'py, f64>,
    objective: &str,
) -> PyResult<(f64, Bound<'py, PyArray1<f64>>)> {
    let target = target(scene, objective, &keys)?;
    let values = key_values(&keys, &values)?;
    let (value, gradient) = py.detach(|| target.value_and_gradient(&keys, &values)).map_err(scene_error)?;
    Ok((value.value, PyArray1::from_vec(py, gradient)))
}

/// `asnr tolerance` for `scene`: `vary` holds `(key, distribution)` pairs as `--vary KEY=DIST`
/// takes them. Returns its `--json` and `--csv` texts (the same run: the same numbers). The GIL
/// is released while it runs.
#[pyfunction]
#[pyo3(signature = (scene, vary, samples=1000, seed=1, objective="asnr", budget_s=600.0, threads=0))]
#[allow(clippy::too_many_arguments)] // Python's keyword arguments, each one of `asnr tolerance`'s options
fn tolerance(
    py: Python<'_>,
    scene: &Scene,
    vary: Vec<(String, String)>,
    samples: usize,
    seed: u64,
    objective: &str,
    budget_s: f64,
    threads: usize,
) -> PyResult<(String, String)> {
    scene_lens_only(scene, "tolerance")?;
    let varies = vary
        .iter()
        .map(|(k, d)| report::tolerance::parse_vary(&format!("{k}={d}")))
        .collect::<anyhow::Result<Vec<_>>>()
        .map_err(scene_error)?;
    let objective = report::objective::Objective::parse(objective).map_err(scene_error)?;
    let keys: Vec<String> = varies.iter().map(|v| v.key.clone()).collect();
    let settings = report::tolerance::Settings { samples, seed, budget_s, threads };
    let t = py
        .detach(|| {
            let target =
                report::objective::Target::new(scene.source.clone(), scene.overrides.clone(), objective, &keys)?;
            report::tolerance::tolerance(&target, &varies, &settings, &())
        })
        .map_err(scene_error)?;
    Ok((report::tolerance::json(&t).map_err(scene_error)?, report::tolerance::csv(&t)))
}

/// A lens written in Python: `f_number`, `focal_length_m`, optional `design_wavelength_m`, and
/// `orders(wavelength_m, (field_x_rad, field_y_rad))` returning the imaging orders, each an object
/// (or dict) with `efficiency` and `defocus_m` and optionally `image_shift_m` (x, y), the Seidel
/// terms `spherical_m`, `coma_m`, `astigmatism_m`, `field_curvature_m`, Zernike terms
/// `zernike_noll_m` (Noll order from Z1, m RMS) and radial terms `radial_m` (`Σ c_i ρ^{2i}`, m);
/// optional
/// `transmission(wavelength_m)`. All in SI units, the wavefront sign of docs/physics.md. The first
/// error raised in a callback is kept and raised when the evaluation returns.
#[derive(Debug)]
struct PyLens {
    object: Py<PyAny>,
    name: String,
    f_number: f64,
    focal_length: f64,
    design_wavelength: Option<f64>,
    has_transmission: bool,
    error: Mutex<Option<PyErr>>,
}

impl PyLens {
    fn new(object: &Bound<'_, PyAny>) -> PyResult<PyLens> {
        let name = object.get_type().name()?.to_string();
        let number = |attr: &str| -> PyResult<f64> {
            let v: f64 = object.getattr(attr).and_then(|v| v.extract()).map_err(|e| {
                PyTypeError::new_err(format!("{name}.{attr}: {e}: a LensModel needs f_number and focal_length_m (m)"))
            })?;
            if !(v.is_finite() && v > 0.0) {
                return Err(PyValueError::new_err(format!("{name}.{attr} = {v}: expected a finite number > 0")));
            }
            Ok(v)
        };
        let f_number = number("f_number")?;
        let focal_length = number("focal_length_m")?;
        let design_wavelength = match object.getattr("design_wavelength_m") {
            Ok(v) if !v.is_none() => Some(v.extract::<f64>()?),
            _ => None,
        };
        if !object.getattr("orders").is_ok_and(|o| o.is_callable()) {
            return Err(PyTypeError::new_err(format!(
                "{name} has no method orders(wavelength_m, field): a LensModel returns its imaging orders"
            )));
        }
        let has_transmission = object.getattr("transmission").is_ok_and(|t| t.is_callable());
        Ok(PyLens {
            object: object.clone().unbind(),
            name,
            f_number,
            focal_length,
            design_wavelength,
            has_transmission,
            error: Mutex::new(None),
        })
    }

    /// Keeps the first error a callback raised.
    fn keep(&self, e: PyErr) {
        if let Ok(mut slot) = self.error.lock() {
            slot.get_or_insert(e);
        }
    }

    /// Raises (and clears) the error a callback raised, if any.
    fn raise(&self) -> PyResult<()> {
        match self.error.lock().ok().and_then(|mut slot| slot.take()) {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    fn call_orders(&self, py: Python<'_>, wavelength_m: f64, field: Field) -> PyResult<Vec<Order>> {
        let list = self.object.bind(py).call_method1("orders", (wavelength_m, (field.x_rad, field.y_rad)))?;
        let mut orders = Vec::new();
        for item in list.try_iter()? {
            let item = item?;
            let get = |attr: &str| -> PyResult<Option<Bound<'_, PyAny>>> {
                if let Ok(d) = item.cast::<PyDict>() {
                    return d.get_item(attr);
                }
                if let Ok(t) = item.cast::<PyTuple>() {
                    // (efficiency, defocus_m)
                    return match attr {
                        "efficiency" => t.get_item(0).map(Some),
                        "defocus_m" => t.get_item(1).map(Some),
                        _ => Ok(None),
                    };
                }
                match item.getattr(attr) {
                    Ok(v) if !v.is_none() => Ok(Some(v)),
                    _ => Ok(None),
                }
            };
            let number = |attr: &str, default: Option<f64>| -> PyResult<f64> {
                let v = match get(attr)? {
                    Some(v) => v.extract::<f64>()?,
                    None => default.ok_or_else(|| {
                        PyValueError::new_err(format!(
                            "{}.orders({wavelength_m:e}): an order without {attr}",
                            self.name
                        ))
                    })?,
                };
                if !v.is_finite() {
                    return Err(PyValueError::new_err(format!(
                        "{}.orders({wavelength_m:e}): {attr} = {v}: expected a finite number",
                        self.name
                    )));
                }
                Ok(v)
            };
            let efficiency = number("efficiency", None)?;
            if !(0.0..=1.0).contains(&efficiency) {
                return Err(PyValueError::new_err(format!(
                    "{}.orders({wavelength_m:e}): efficiency = {efficiency}: expected a fraction in [0, 1]",
                    self.name
                )));
            }
            let mut wavefront = Wavefront::defocus(number("defocus_m", None)?);
            wavefront.spherical_m = number("spherical_m", Some(0.0))?;
            wavefront.coma_m = number("coma_m", Some(0.0))?;
            wavefront.astigmatism_m = number("astigmatism_m", Some(0.0))?;
            wavefront.field_curvature_m = number("field_curvature_m", Some(0.0))?;
            if let Some(shift) = get("image_shift_m")? {
                let (x, y): (f64, f64) = shift.extract()?;
                wavefront = wavefront.shifted(x, y);
            }
            let list = |attr: &str| -> PyResult<Vec<f64>> {
                let values: Vec<f64> = match get(attr)? {
                    Some(v) => v.extract()?,
                    None => Vec::new(),
                };
                if let Some(bad) = values.iter().find(|v| !v.is_finite()) {
                    return Err(PyValueError::new_err(format!(
                        "{}.orders({wavelength_m:e}): {attr} holds {bad}: expected finite numbers",
                        self.name
                    )));
                }
                Ok(values)
            };
            let zernike = list("zernike_noll_m")?;
            let radial = list("radial_m")?;
            if zernike.is_empty() && radial.is_empty() {
                orders.push(Order::new(efficiency, Pupil::Full, wavefront));
                continue;
            }
            // Zernike terms (Noll order from Z1, m RMS) and radial terms Σ c_i ρ^{2i} (m): a
            // radial pupil (the radial engine where symmetric, the FFT path otherwise)
            let invalid =
                |e: optics::Error| PyValueError::new_err(format!("{}.orders({wavelength_m:e}): {e}", self.name));
            let terms: Vec<(usize, f64)> =
                zernike.iter().enumerate().filter(|(_, c)| **c != 0.0).map(|(i, &c)| (i + 1, c)).collect();
            let profile = optics::radial::RadialProfile::even_polynomial(radial).map_err(invalid)?;
            let pupil = optics::radial::RadialPupil::new(None, vec![(1.0, std::sync::Arc::new(profile))], terms)
                .map_err(invalid)?;
            orders.push(Order::radial(efficiency, std::sync::Arc::new(pupil), wavefront));
        }
        Ok(orders)
    }
}

impl LensModel for PyLens {
    fn f_number(&self) -> f64 {
        self.f_number
    }

    fn focal_length(&self) -> f64 {
        self.focal_length
    }

    fn orders(&self, wavelength_m: f64, field: Field) -> Vec<Order> {
        Python::attach(|py| {
            self.call_orders(py, wavelength_m, field).unwrap_or_else(|e| {
                self.keep(e);
                Vec::new()
            })
        })
    }

    fn transmission(&self, wavelength_m: f64) -> f64 {
        if !self.has_transmission {
            return self.efficiency(wavelength_m);
        }
        Python::attach(|py| {
            let t = self.object.bind(py).call_method1("transmission", (wavelength_m,)).and_then(|t| t.extract::<f64>());
            t.and_then(|t| {
                if (0.0..=1.0).contains(&t) {
                    Ok(t)
                } else {
                    Err(PyValueError::new_err(format!(
                        "{}.transmission({wavelength_m:e}) = {t}: expected a fraction in [0, 1]",
                        self.name
                    )))
                }
            })
            .unwrap_or_else(|e| {
                self.keep(e);
                0.0
            })
        })
    }

    fn design_wavelength(&self) -> Option<f64> {
        self.design_wavelength
    }

    fn describe(&self) -> String {
        format!("{} (Python) F/{} f0 = {} mm", self.name, self.f_number, self.focal_length * 1e3)
    }
}

/// The native module.
#[pymodule]
fn _asnr(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("SceneError", m.py().get_type::<SceneError>())?;
    m.add_class::<Scene>()?;
    m.add_function(wrap_pyfunction!(load_file, m)?)?;
    m.add_function(wrap_pyfunction!(_rebuild_scene, m)?)?;
    m.add_function(wrap_pyfunction!(load_text, m)?)?;
    m.add_function(wrap_pyfunction!(load_json, m)?)?;
    m.add_function(wrap_pyfunction!(evaluate, m)?)?;
    m.add_function(wrap_pyfunction!(evaluate_many, m)?)?;
    m.add_function(wrap_pyfunction!(axis, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_csv, m)?)?;
    m.add_function(wrap_pyfunction!(mtf, m)?)?;
    m.add_function(wrap_pyfunction!(compare, m)?)?;
    m.add_function(wrap_pyfunction!(optimize, m)?)?;
    m.add_function(wrap_pyfunction!(tolerance, m)?)?;
    m.add_function(wrap_pyfunction!(gradient, m)?)?;
    m.add_function(wrap_pyfunction!(check_objective, m)?)?;
    m.add_function(wrap_pyfunction!(objective_value, m)?)?;
    m.add_function(wrap_pyfunction!(objective_value_and_gradient, m)?)?;
    m.add_function(wrap_pyfunction!(sfr, m)?)?;
    m.add_function(wrap_pyfunction!(measure, m)?)?;
    Ok(())
}
