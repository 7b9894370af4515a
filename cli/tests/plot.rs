//! End-to-end tests of `asnr plot`: sweep CSVs replotted as overlaid lines (grouped, shaded,
//! marked) or as a heatmap, and bad input; and of the figures every plotting command draws
//! (`asnr plot`, `sweep --plot`, `mtf --plot`): human axis labels, the given title, the legend
//! outside the data, references on top, swatches stroked like their lines, PNG size and
//! resolution.
//!
//! Every bad-input case asserts exit code 1, no panic, and a message that names the file, the
//! column (or option), the value and what is accepted.

use std::path::{Path, PathBuf};

mod common;

use common::{asnr, fails, stderr};

/// Runs `asnr` expecting success.
fn succeeds(args: &[&str]) {
    let out = asnr(args);
    assert!(out.status.success(), "args {args:?}: {}", stderr(&out));
}

/// A scratch directory unique to one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("asnr-plot-test-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Writes `text` to `dir/name` and returns the path as a string.
fn file(dir: &Path, name: &str, text: &str) -> String {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path.to_str().unwrap().to_owned()
}

const HEADER: &str = "lens.f_number,spectrum.range_nm,mean_mtf,snr0,asnr,photoelectrons,fraunhofer_valid\n";

/// A 2 × 3 grid in sweep order, the last range beyond Fraunhofer validity at F/1.5.
fn grid_csv() -> String {
    let mut text = format!("# a comment line\n{HEADER}");
    for (f, r, asnr, valid) in [
        (1.5, 10.0, 9.0, true),
        (1.5, 50.0, 11.0, true),
        (1.5, 300.0, 8.0, false),
        (2.5, 10.0, 7.0, true),
        (2.5, 50.0, 10.0, true),
        (2.5, 300.0, 7.5, true),
    ] {
        text.push_str(&format!("{f},{r},0.5,20,{asnr},400,{valid}\n"));
    }
    text
}

/// The contents of the SVG's `<text>` elements, trimmed.
fn texts(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| Some(t.split_once('>')?.1.split_once("</text>")?.0.trim().to_owned()))
        .collect()
}

fn svg(path: &Path) -> String {
    let text = std::fs::read_to_string(path).expect("the plot was written");
    assert!(text.starts_with("<svg"), "{}", &text[..text.len().min(200)]);
    text
}

#[test]
fn overlays_labelled_csvs_with_marks_and_best_points() {
    let dir = scratch("overlay");
    let theory = file(&dir, "theory.csv", "spectrum.range_nm,asnr\n10,8\n30,10.5\n50,10.3\n");
    let simulated = file(&dir, "sim.csv", "spectrum.range_nm,asnr\n50,9.2\n10,7.5\n30,9.6\n"); // unsorted is fine
    let out = dir.join("fig.svg");
    succeeds(&[
        "plot",
        &format!("{theory}=theory"),
        &simulated,
        "--x",
        "spectrum.range_nm",
        "--y",
        "asnr",
        "--mark-best",
        "--mark-x",
        "10=filters",
        "--mark-x",
        "40=filters",
        "--title",
        "Fig. 2b test",
        "-o",
        out.to_str().unwrap(),
    ]);
    let text = svg(&out);
    // the maxima are refined by the parabola through the best sample and its neighbours
    for needle in ["Fig. 2b test", "theory: max 10.74 at 38.52 nm", "sim: max 9.745 at 36.8 nm", "filters"] {
        assert!(text.contains(needle), "missing {needle:?}");
    }
    // marks with the same label share one legend entry
    assert_eq!(texts(&text).iter().filter(|t| *t == "filters").count(), 1, "{:?}", texts(&text));
}

#[test]
fn groups_one_csv_into_lines_and_shades_invalid_points() {
    let dir = scratch("group");
    let csv = file(&dir, "grid.csv", &grid_csv());
    let plot = |out: &std::path::Path| {
        succeeds(&[
            "plot",
            &csv,
            "--x",
            "spectrum.range_nm",
            "--y",
            "asnr",
            "--group",
            "lens.f_number",
            "--group-label",
            "F/{}",
            "--shade-invalid",
            "--output",
            out.to_str().unwrap(),
        ]);
    };
    let out = dir.join("s9.png");
    plot(&out);
    assert_eq!(&std::fs::read(&out).unwrap()[..4], b"\x89PNG");
    let out = dir.join("s9.svg");
    plot(&out);
    let texts = texts(&svg(&out));
    for needle in ["F/1.5", "F/2.5", "Fraunhofer approximation not valid (SI eq. S15)"] {
        assert!(texts.iter().any(|t| t == needle), "missing {needle:?} in {texts:?}");
    }
}

#[test]
fn heatmap_of_a_sweep_csv_with_ridge_mark_and_shading() {
    let dir = scratch("heatmap");
    let csv = file(&dir, "grid.csv", &grid_csv());
    let out = dir.join("fig2a.svg");
    succeeds(&[
        "plot",
        &csv,
        "--x",
        "lens.f_number",
        "--y",
        "spectrum.range_nm",
        "--z",
        "asnr",
        "--x-label",
        "F-number",
        "--z-label",
        "ASNR",
        "--mark-x",
        "2.5=F/2.5",
        "--shade-invalid",
        "-o",
        out.to_str().unwrap(),
    ]);
    // the legend lies outside the heatmap and its colour bar
    let lines = polylines(&svg(&out));
    let legend = outline(&lines, LEGEND_EDGE).expect("a legend box");
    let frames: Vec<Rect> = lines
        .iter()
        .filter(|l| l.stroke == FRAME && l.points.len() >= 5 && l.points.first() == l.points.get(4))
        .map(Polyline::bounds)
        .collect();
    assert_eq!(frames.len(), 2, "the heatmap's and the colour bar's frames: {frames:?}");
    assert!(frames.iter().all(|f| !f.overlaps(&legend)), "legend {legend:?} over {frames:?}");
    let texts = texts(&svg(&out));
    for needle in [
        "max ASNR for each F-number",
        "F/2.5",
        "Fraunhofer approximation not valid (SI eq. S15)",
        "ASNR vs F-number and spectral range",
        "spectral range (nm)",
    ] {
        assert!(texts.iter().any(|t| t == needle), "missing {needle:?} in {texts:?}");
    }
}

#[test]
fn replots_what_sweep_writes() {
    let dir = scratch("sweep");
    let out = asnr(&["sweep", "--over", "spectrum.range_nm=10:50:3", "--csv"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let csv = file(&dir, "sweep.csv", &String::from_utf8(out.stdout).unwrap());
    let svg_path = dir.join("sweep.svg");
    succeeds(&["plot", &csv, "--x", "spectrum.range_nm", "--y", "mean_mtf", "-o", svg_path.to_str().unwrap()]);
    let texts = texts(&svg(&svg_path));
    for needle in ["mean MTF vs spectral range", "spectral range (nm)", "mean MTF"] {
        assert!(texts.iter().any(|t| t == needle), "missing {needle:?} in {texts:?}");
    }
    assert!(!texts.iter().any(|t| t.contains("spectrum.range_nm") || t.contains("mean_mtf")), "{texts:?}");
}

#[test]
fn bad_files_and_columns_are_named() {
    let dir = scratch("bad");
    let out = dir.join("x.svg");
    let out = out.to_str().unwrap();
    let grid = file(&dir, "grid.csv", &grid_csv());

    let missing = dir.join("missing.csv");
    let err = fails(&["plot", missing.to_str().unwrap(), "--x", "a", "--y", "b", "-o", out]);
    assert!(err.contains("missing.csv: cannot read the CSV file"), "{err}");

    let err = fails(&["plot", &grid, "--x", "spectrum.range", "--y", "asnr", "-o", out]);
    assert!(err.contains("grid.csv: no column `spectrum.range` (--x); the columns are: lens.f_number,"), "{err}");

    let bad = file(&dir, "bad-number.csv", "spectrum.range_nm,asnr\n10,8\n30,abc\n");
    let err = fails(&["plot", &bad, "--x", "spectrum.range_nm", "--y", "asnr", "-o", out]);
    assert!(
        err.contains("bad-number.csv line 3, column `asnr`: `abc` is not a finite number; expected a number"),
        "{err}"
    );

    let bad = file(&dir, "bad-flag.csv", "x,asnr,fraunhofer_valid\n10,8,true\n30,9,yes\n");
    let err = fails(&["plot", &bad, "--x", "x", "--y", "asnr", "--shade-invalid", "-o", out]);
    assert!(err.contains("bad-flag.csv line 3, column `fraunhofer_valid`: `yes`; expected true or false"), "{err}");

    let plain = file(&dir, "plain.csv", "x,asnr\n10,8\n30,9\n");
    let err = fails(&["plot", &plain, "--x", "x", "--y", "asnr", "--shade-invalid", "-o", out]);
    assert!(err.contains("plain.csv: no column `fraunhofer_valid` (--shade-invalid)"), "{err}");

    let ragged = file(&dir, "ragged.csv", "x,asnr\n10,8\n30\n");
    let err = fails(&["plot", &ragged, "--x", "x", "--y", "asnr", "-o", out]);
    assert!(err.contains("ragged.csv line 3:") && err.contains("expected 2 comma-separated fields"), "{err}");

    let empty = file(&dir, "empty.csv", "x,asnr\n");
    let err = fails(&["plot", &empty, "--x", "x", "--y", "asnr", "-o", out]);
    assert!(err.contains("empty.csv: no data rows"), "{err}");

    // a two-key sweep drawn as lines without --group repeats x
    let err = fails(&["plot", &grid, "--x", "spectrum.range_nm", "--y", "asnr", "-o", out]);
    assert!(err.contains("grid.csv: column `spectrum.range_nm` (--x) has the value 10 twice"), "{err}");
    assert!(err.contains("--group COLUMN"), "{err}");

    let err = fails(&["plot", &plain, "--x", "x", "--y", "asnr", "-o", "/tmp/asnr-plot.pdf"]);
    assert!(err.contains("--output /tmp/asnr-plot.pdf: expected a file name ending in .svg or .png"), "{err}");

    let err = fails(&["plot", &plain, "--x", "x", "--y", "asnr", "--mark-x", "ten=filters", "-o", out]);
    assert!(err.contains("--mark-x ten=filters: `ten` is not a finite number; expected X or X=LABEL"), "{err}");
}

#[test]
fn bad_heatmap_grids_are_named() {
    let dir = scratch("bad-grid");
    let out = dir.join("x.svg");
    let out = out.to_str().unwrap();
    let heat = ["--x", "lens.f_number", "--y", "spectrum.range_nm", "--z", "asnr", "-o", out];

    let text = grid_csv();
    let incomplete = file(&dir, "incomplete.csv", &text[..text.trim_end().rfind('\n').unwrap()]);
    let err = fails(&[&["plot", incomplete.as_str()], &heat[..]].concat());
    assert!(
        err.contains(
            "incomplete.csv: the grid of lens.f_number × spectrum.range_nm is incomplete: no row for \
             lens.f_number = 2.5, spectrum.range_nm = 300"
        ),
        "{err}"
    );

    let twice = file(&dir, "twice.csv", &format!("{text}1.5,10,0.5,20,9,400,true\n"));
    let err = fails(&[&["plot", twice.as_str()], &heat[..]].concat());
    assert!(
        err.contains("twice.csv: lens.f_number = 1.5, spectrum.range_nm = 10 appears twice (lines 3 and 9)"),
        "{err}"
    );

    let grid = file(&dir, "grid.csv", &text);
    let err = fails(&[&["plot", grid.as_str(), grid.as_str()], &heat[..]].concat());
    assert!(err.contains("--z asnr: a heatmap is drawn from one CSV; got 2 files"), "{err}");
}

const PAPER: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/paper-theory.toml");
const MONOCHROMATIC: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/monochromatic.toml");

/// The value of attribute `name` in the text of one SVG tag.
fn attr<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let start = tag.find(&format!(" {name}=\""))? + name.len() + 3;
    Some(&tag[start..start + tag[start..].find('"')?])
}

/// An SVG polyline: its stroke colour and width, and its points.
#[derive(Debug)]
struct Polyline {
    stroke: String,
    width: f64,
    points: Vec<(f64, f64)>,
}

impl Polyline {
    fn bounds(&self) -> Rect {
        let fold = |f: fn(f64, f64) -> f64, init: f64, pick: fn(&(f64, f64)) -> f64| {
            self.points.iter().map(pick).fold(init, f)
        };
        Rect {
            x0: fold(f64::min, f64::INFINITY, |p| p.0),
            y0: fold(f64::min, f64::INFINITY, |p| p.1),
            x1: fold(f64::max, f64::NEG_INFINITY, |p| p.0),
            y1: fold(f64::max, f64::NEG_INFINITY, |p| p.1),
        }
    }
}

/// The SVG's polylines in drawing order.
fn polylines(svg: &str) -> Vec<Polyline> {
    svg.split("<polyline")
        .skip(1)
        .filter_map(|t| {
            let tag = t.split("/>").next()?;
            let points = attr(tag, "points")?
                .split_whitespace()
                .filter_map(|p| {
                    let (x, y) = p.split_once(',')?;
                    Some((x.parse().ok()?, y.parse().ok()?))
                })
                .collect();
            Some(Polyline {
                stroke: attr(tag, "stroke")?.to_owned(),
                width: attr(tag, "stroke-width")?.parse().ok()?,
                points,
            })
        })
        .collect()
}

#[derive(Clone, Copy, Debug)]
struct Rect {
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
}

impl Rect {
    fn contains(&self, other: &Rect) -> bool {
        other.x0 >= self.x0 - 1.0 && other.x1 <= self.x1 + 1.0 && other.y0 >= self.y0 - 1.0 && other.y1 <= self.y1 + 1.0
    }

    fn overlaps(&self, other: &Rect) -> bool {
        self.x0 < other.x1 && other.x0 < self.x1 && self.y0 < other.y1 && other.y0 < self.y1
    }

    fn area(&self) -> f64 {
        (self.x1 - self.x0) * (self.y1 - self.y0)
    }
}

/// The closed rectangular outline stroked in `stroke` with the largest area: the plotting area's
/// frame (black) or the legend's box (grey).
fn outline(lines: &[Polyline], stroke: &str) -> Option<Rect> {
    lines
        .iter()
        .filter(|l| l.stroke == stroke && l.points.len() >= 5 && l.points.first() == l.points.get(4))
        .map(Polyline::bounds)
        .max_by(|a, b| a.area().total_cmp(&b.area()))
}

const FRAME: &str = "#000000";
const LEGEND_EDGE: &str = "#969696";
const GRID: &str = "#DEDEDE";
/// The first series colour, the polychromatic MTF's.
const BLUE: &str = "#1450C8";

#[test]
fn the_legend_is_outside_the_data_and_every_curve_inside_it() {
    let dir = scratch("legend");
    // rising to the upper right corner, where a legend inside the chart would sit
    let rising = file(&dir, "rising.csv", "spectrum.range_nm,asnr\n0,0\n10,6\n20,9\n30,10\n");
    let falling = file(&dir, "falling.csv", "spectrum.range_nm,asnr\n0,10\n10,4\n20,9\n30,8\n");
    for (name, extra) in [("wide.svg", &[][..]), ("column.svg", &["--width", "1050", "--dpi", "300"][..])] {
        let out = dir.join(name);
        let mut args = vec!["plot", &rising, &falling, "--x", "spectrum.range_nm", "--y", "asnr", "--mark-best"];
        args.extend(["--mark-x", "15=a reference line", "-o", out.to_str().unwrap()]);
        args.extend(extra);
        succeeds(&args);
        let lines = polylines(&svg(&out));
        let frame = outline(&lines, FRAME).expect("a frame around the plotting area");
        let legend = outline(&lines, LEGEND_EDGE).expect("a legend box");
        assert!(!frame.overlaps(&legend), "{name}: legend {legend:?} overlaps the plotting area {frame:?}");
        let curves: Vec<&Polyline> = lines.iter().filter(|l| l.stroke == BLUE).collect();
        assert!(curves.len() >= 2, "{name}: {curves:?}");
        for curve in curves {
            let b = curve.bounds();
            assert!(frame.contains(&b) || legend.contains(&b), "{name}: {curve:?} is neither data nor swatch");
        }
    }
}

#[test]
fn mtf_references_are_drawn_last_and_dashed_lines_have_dashed_swatches() {
    let dir = scratch("mtf-styles");
    let out = dir.join("mtf.svg");
    succeeds(&[
        "mtf",
        "--set",
        "field.x_deg=8",
        "--wavelengths",
        "800",
        "--points",
        "41",
        "--plot",
        out.to_str().unwrap(),
    ]);
    let lines = polylines(&svg(&out));
    let frame = outline(&lines, FRAME).unwrap();
    let legend = outline(&lines, LEGEND_EDGE).unwrap();
    let inside = |l: &&Polyline, r: &Rect| r.contains(&l.bounds());
    // the curves: inside the frame, neither grid lines nor the axes and frame (black, as thin as the frame)
    let frame_width = lines.iter().find(|l| l.stroke == FRAME && l.bounds().area() == frame.area()).unwrap().width;
    let data: Vec<&Polyline> = lines
        .iter()
        .filter(|l| inside(l, &frame) && l.stroke != GRID && !(l.stroke == FRAME && l.width == frame_width))
        .collect();
    // the diffraction limit: black, dashed (many pieces), after every other curve
    let last_poly = data.iter().rposition(|l| l.stroke == BLUE).expect("the polychromatic MTF");
    let first_reference = data.iter().position(|l| l.stroke == FRAME).expect("the diffraction limit");
    assert!(last_poly < first_reference, "the reference is drawn at {first_reference}, the MTF at {last_poly}");
    let reference = data.iter().filter(|l| l.stroke == FRAME).count();
    assert!(reference > 10, "the diffraction limit in {reference} dashes");
    // each legend swatch has its line's stroke: colour, width, and dashes (several pieces)
    let swatches: Vec<&Polyline> = lines.iter().filter(|l| inside(l, &legend) && l.stroke != LEGEND_EDGE).collect();
    let mut dashed = 0;
    for stroke in data.iter().map(|l| l.stroke.clone()).collect::<std::collections::BTreeSet<_>>() {
        let in_plot: Vec<&&Polyline> = data.iter().filter(|l| l.stroke == stroke).collect();
        let in_legend: Vec<&&Polyline> = swatches.iter().filter(|l| l.stroke == stroke).collect();
        assert!(!in_legend.is_empty(), "no swatch for {stroke}");
        assert_eq!(in_plot[0].width, in_legend[0].width, "{stroke}: width in the plot and in the legend");
        // a line drawn in pieces (dashed) has a swatch in pieces; a solid line one piece
        if in_plot.len() > 3 {
            dashed += 1;
            assert!(in_legend.len() >= 2, "{stroke}: a dashed line with a solid swatch");
        } else {
            assert_eq!(in_legend.len(), 1, "{stroke}: a solid line with a dashed swatch");
        }
    }
    // the two off-axis directions and the diffraction limit
    assert_eq!(dashed, 3);
}

/// `mtf --plot` of a field-of-view average whose pupil is 2-D (coma, the non-radial Zernike term
/// Z7, sampled on the pupil grid): each field point's mean over azimuth, tangential and sagittal
/// MTFs are drawn inside the axes in the point's colour (the mean solid and wider, the two
/// directions dashed), each with a legend entry naming the point's field angles and the direction, on axes
/// labelled with their units; the JSON says what the mean is.
#[test]
fn mtf_plot_draws_each_field_points_directional_curves() {
    let dir = scratch("mtf-directions");
    let fields = "[[fields]]\nx_deg = 0\nweight = 1\n\n[[fields]]\nx_deg = 8\nweight = 3\n\n[camera]";
    let scene = file(&dir, "fields.toml", &std::fs::read_to_string(PAPER).unwrap().replace("[camera]", fields));
    let coma = "lens.zernike_noll_rms_um=[0,0,0,0,0,0,0.1]";
    let out = dir.join("mtf.svg");
    succeeds(&["mtf", &scene, "--set", coma, "--points", "21", "--plot", out.to_str().unwrap()]);
    let text = svg(&out);
    let all = texts(&text);
    for needle in [
        "polychromatic MTF, weighted mean of 2 field points",
        "on axis: mean over azimuth",
        "on axis: along x",
        "on axis: along y",
        "field (8°, 0°): mean over azimuth",
        "field (8°, 0°): tangential (along the field)",
        "field (8°, 0°): sagittal (across the field)",
        "spatial frequency (cycles/mm)",
        "MTF",
    ] {
        assert!(all.iter().any(|t| t == needle), "missing {needle:?} in {all:?}");
    }
    // each point's curves in its colour (the palette's second and third) inside the frame: the
    // mean one solid line, the widest, the two directions dashed (many thinner pieces)
    let lines = polylines(&text);
    let frame = outline(&lines, FRAME).unwrap();
    for colour in ["#D72828", "#EBA000"] {
        let inside: Vec<&Polyline> =
            lines.iter().filter(|l| l.stroke == colour && frame.contains(&l.bounds())).collect();
        let widths: Vec<f64> = inside.iter().map(|l| l.width).collect();
        let widest = widths.iter().copied().fold(0.0, f64::max);
        let solid = inside.iter().filter(|l| l.width == widest).count();
        let dashed = inside.iter().filter(|l| l.width < widest).count();
        assert_eq!(solid, 1, "{colour}: the mean as one solid line ({widths:?})");
        assert!(dashed > 10, "{colour}: the two directions in {dashed} dashes");
    }
    let out = asnr(&["mtf", &scene, "--set", coma, "--points", "5", "--json"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let json = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(json.contains("\"mtf_over_azimuth\": true"), "{json}");
    assert!(json.contains("weighted mean over 2 field points of the means over azimuth"), "{json}");
}

/// The texts of the title: those above the plotting area.
fn title(svg: &str) -> String {
    let frame = outline(&polylines(svg), FRAME).unwrap();
    svg.split("<text")
        .skip(1)
        .filter_map(|t| {
            let y: f64 = attr(t, "y")?.parse().ok()?;
            let text = t.split_once('>')?.1.split_once("</text>")?.0.trim().to_owned();
            (y < frame.y0 && attr(t, "transform").is_none()).then_some(text)
        })
        .collect::<Vec<_>>()
        .join(" ")
}

#[test]
fn sweep_and_mtf_plots_show_what_was_swept_and_human_axis_labels() {
    let dir = scratch("titles");
    let lens = "chromatic metalens F/2.5 f0 = 3.36 mm at λ0 = 800 nm";
    let out = dir.join("sweep.svg");
    succeeds(&["sweep", PAPER, "--over", "camera.pixel_pitch_um=4:6:3", "--plot", out.to_str().unwrap()]);
    let text = svg(&out);
    // what was swept, not the scene's title (its "50 nm range" is what a band sweep replaces)
    // and the field point the curves are computed at
    assert_eq!(title(&text), format!("ASNR over pixel pitch 4–6 µm: {lens}, on axis"));
    let all = texts(&text);
    assert!(!all.iter().any(|t| t.contains(".toml") || t.contains("examples")), "{all:?}");
    for needle in ["pixel pitch (µm)", "ASNR"] {
        assert!(all.iter().any(|t| t == needle), "missing {needle:?} in {all:?}");
    }
    assert!(!all.iter().any(|t| t.contains("camera.pixel_pitch_um")), "{all:?}");

    let out = dir.join("heat.svg");
    succeeds(&[
        "sweep",
        "--over",
        "spectrum.range_nm=10:50:3",
        "--over",
        "exposure.time_ms=1:2:2",
        "--plot",
        out.to_str().unwrap(),
    ]);
    let text = svg(&out);
    assert_eq!(title(&text), format!("ASNR over spectral range 10–50 nm and exposure time 1–2 ms: {lens}, on axis"));
    // a swept lens key makes the lens description stale: left out
    let out = dir.join("f-number.svg");
    succeeds(&["sweep", "--over", "lens.f_number=2:4:3", "--plot", out.to_str().unwrap()]);
    assert_eq!(title(&svg(&out)), "ASNR over F-number 2–4, on axis");
    let all = texts(&text);
    for needle in ["spectral range (nm)", "exposure time (ms)", "best exposure time for each spectral range"] {
        assert!(all.iter().any(|t| t == needle), "missing {needle:?} in {all:?}");
    }

    let out = dir.join("mtf.svg");
    succeeds(&["mtf", MONOCHROMATIC, "--points", "21", "--plot", out.to_str().unwrap()]);
    let text = svg(&out);
    let expected = "Paper lens F/2.5 behind a 1 nm line filter at 800 nm (one wavelength for the optics), on axis";
    assert_eq!(title(&text), expected);
    assert!(texts(&text).iter().any(|t| t == "spatial frequency (cycles/mm)"));
    assert!(!texts(&text).iter().any(|t| t.contains(".toml")));
}

/// Width and the pHYs resolution (pixels per metre, unit) of a PNG file.
fn png_header(path: &Path) -> (u32, Option<(u32, u32, u8)>) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    let be = |i: usize| u32::from_be_bytes(bytes[i..i + 4].try_into().unwrap());
    assert_eq!(&bytes[12..16], b"IHDR");
    let width = be(16);
    let at = bytes.windows(4).position(|w| w == b"pHYs");
    (width, at.map(|i| (be(i + 4), be(i + 8), bytes[i + 12])))
}

/// The font sizes of an SVG's texts in points, for a figure shown at `dpi`.
fn font_points(svg: &str, dpi: f64) -> Vec<f64> {
    let header = svg.split_once('>').unwrap().0;
    let shown: f64 = attr(header, "width").unwrap().parse().unwrap();
    let drawn: f64 = attr(header, "viewBox").unwrap().split_whitespace().nth(2).unwrap().parse().unwrap();
    svg.split("<text")
        .skip(1)
        .filter_map(|t| attr(t, "font-size")?.parse::<f64>().ok())
        .map(|size| size * shown / drawn / dpi * 72.0)
        .collect()
}

#[test]
fn width_and_dpi_set_the_png_size_its_resolution_and_the_text_size() {
    let dir = scratch("dpi");
    let csv = file(&dir, "line.csv", "spectrum.range_nm,asnr\n10,8\n30,10.5\n50,10.3\n");
    let plot = |extra: &[&str], name: &str| {
        let out = dir.join(name);
        let mut args =
            vec!["plot", csv.as_str(), "--x", "spectrum.range_nm", "--y", "asnr", "-o", out.to_str().unwrap()];
        args.extend(extra);
        succeeds(&args);
        out
    };
    // 1200 px at 300 dpi: 11811 pixels per metre
    assert_eq!(png_header(&plot(&["--width", "1200", "--dpi", "300"], "a.png")), (1200, Some((11_811, 11_811, 1))));
    // by default 900 px, a 6-inch figure: 150 dpi
    assert_eq!(png_header(&plot(&[], "b.png")), (900, Some((5906, 5906, 1))));
    // a 3.5-inch column at 300 dpi has 8–10 pt text
    let column = svg(&plot(&["--width", "1050", "--dpi", "300"], "c.svg"));
    assert!(column.starts_with("<svg width=\"1050\""), "{}", &column[..80]);
    let points = font_points(&column, 300.0);
    assert!(!points.is_empty() && points.iter().all(|p| (7.9..=10.1).contains(p)), "{points:?}");
    // the same width at the default resolution (175 dpi for 1050 px) has smaller text
    let default = svg(&plot(&["--width", "1050"], "d.svg"));
    let ratio = font_points(&column, 1.0)[0] / font_points(&default, 1.0)[0];
    assert!((ratio - 300.0 / 175.0).abs() < 1e-6, "{ratio}");

    let out = dir.join("x.png");
    let out = out.to_str().unwrap();
    let base = ["plot", csv.as_str(), "--x", "spectrum.range_nm", "--y", "asnr", "-o", out];
    let err = fails(&[&base[..], &["--width", "100"]].concat());
    assert!(err.contains("--width 100: expected a whole number of pixels from 300 to 4000"), "{err}");
    let err = fails(&[&base[..], &["--dpi", "0"]].concat());
    assert!(err.contains("--dpi 0: expected dots per inch from 30 to 2400"), "{err}");
    let err = fails(&[&base[..], &["--dpi", "NaN"]].concat());
    assert!(err.contains("--dpi NaN: expected dots per inch"), "{err}");
    let err = fails(&[&base[..], &["--width", "400", "--dpi", "600"]].concat());
    assert!(err.contains("--dpi 600 with --width 400: the figure would be 0.67 inches wide"), "{err}");
    let err = fails(&["mtf", "--width", "100", "--plot", out]);
    assert!(err.contains("--width 100: expected a whole number of pixels"), "{err}");
    // the flags without a plot are refused, not ignored
    let run = asnr(&["mtf", "--width", "1000"]);
    assert!(!run.status.success() && stderr(&run).contains("--plot"), "{}", stderr(&run));
}

/// Values near the largest double: the padded axis overflows (plotters looped for ever placing
/// the ticks); the plot is refused naming the CSV, the line and the column, never hangs and never
/// prints `inf`; a heatmap's colour values likewise.
#[test]
fn values_near_the_largest_double_are_refused_not_hung() {
    let dir = scratch("huge");
    let lines = file(&dir, "huge.csv", "a,b\n1,1.7e308\n2,1.79e308\n");
    let out = dir.join("huge.svg");
    let err = fails(&["plot", &lines, "--x", "a", "--y", "b", "-o", out.to_str().unwrap()]);
    assert!(err.contains("huge.csv line 2, column `b` (--y): 1.7e308") && !err.contains("inf"), "{err}");
    let grid = file(&dir, "grid.csv", "a,b,c\n1,1,-1.7e308\n1,2,1.7e308\n2,1,0\n2,2,1\n");
    let err = fails(&["plot", &grid, "--x", "a", "--y", "b", "--z", "c", "-o", out.to_str().unwrap()]);
    assert!(err.contains("grid.csv line 2, column `c` (--z): -1.7e308") && !err.contains("inf"), "{err}");
}

/// A --plot or --output file in a folder that does not exist: the folder is named (the system's
/// "No such file or directory" named neither).
#[test]
fn a_missing_output_folder_is_named() {
    let err = fails(&["mtf", "--plot", "/nonexistent-folder/sub/mtf.svg"]);
    assert!(
        err.contains("--plot /nonexistent-folder/sub/mtf.svg: the folder /nonexistent-folder/sub does not exist"),
        "{err}"
    );
}
