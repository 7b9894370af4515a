//! The GDS scale row: `examples/library.toml`'s lens (the paper's aperture, 1.344 mm, on a
//! 400 nm lattice) drawn as a GDSII layout of about 8.9 million 9-vertex pillars (about 0.9 GB,
//! written here into `target/gds-scale/`), read and evaluated as the 2-D library lens
//! (`lens.layout_gds`): the parse, the lens's build, the evaluation, the total, the peak memory
//! and the load, and the ASNR beside the radial library lens of the same layout.

use std::f64::consts::TAU;
use std::path::Path;
use std::time::Instant;

use super::sections::Tools;

const PITCH_NM: f64 = 400.0;
const RADIUS_NM: f64 = 672e3;

/// The fraction of the paper's diameter drawn (`GDS_SCALE_FRACTION`, default 1; the focal length
/// scales with it, the F-number stays): a smaller layout to see how the times scale.
fn fraction() -> f64 {
    std::env::var("GDS_SCALE_FRACTION")
        .ok()
        .and_then(|v| v.parse().ok())
        .filter(|f: &f64| *f > 0.0 && *f <= 1.0)
        .unwrap_or(1.0)
}

/// The layout's rings (`examples/data/layout-paper-lens.csv`: `r_mm, diameter_nm`).
fn rings(root: &Path) -> Option<Vec<f64>> {
    let text = std::fs::read_to_string(root.join("examples/data/layout-paper-lens.csv")).ok()?;
    Some(
        text.lines()
            .filter(|l| !l.starts_with('#') && !l.starts_with("r_mm"))
            .filter_map(|l| l.split(',').nth(1)?.trim().parse().ok())
            .collect(),
    )
}

/// Writes the layout as a GDS (each site within one pitch of the aperture takes the atom of the
/// ring its centre falls in; 9-vertex polygons on a 1 nm grid); returns the pillars written.
fn write(path: &Path, rings: &[f64], radius_nm: f64) -> std::io::Result<u64> {
    let file = std::io::BufWriter::with_capacity(1 << 22, std::fs::File::create(path)?);
    let mut w = scene::gds::Writer::new(file, 1e-9)?;
    w.begin_cell("LENS")?;
    let half = (radius_nm / PITCH_NM).ceil() as i64 + 1;
    let unit: Vec<(f64, f64)> = (0..9).map(|k| (TAU * k as f64 / 9.0).sin_cos()).map(|(s, c)| (c, s)).collect();
    let mut count = 0;
    let mut points = Vec::with_capacity(9);
    for j in -half..=half {
        for i in -half..=half {
            let (x, y) = (i as f64 * PITCH_NM, j as f64 * PITCH_NM);
            let r = x.hypot(y);
            if r > radius_nm + PITCH_NM {
                continue;
            }
            let d = rings[((r / PITCH_NM) as usize).min(rings.len() - 1)];
            points.clear();
            points
                .extend(unit.iter().map(|(c, s)| ((x + 0.5 * d * c).round() as i32, (y + 0.5 * d * s).round() as i32)));
            w.polygon(1, 0, &points)?;
            count += 1;
        }
    }
    w.end_cell()?;
    w.finish()?;
    Ok(count)
}

/// Peak resident memory of this process (`VmHWM`), GiB.
fn peak_gib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / (1024.0 * 1024.0))
}

/// CPU time of this process (user + system, `/proc/self/stat` in ticks of 1/100 s), s: on a
/// shared machine the wall time is the load's, the CPU time the work's.
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    let rest = &stat[stat.rfind(')')? + 1..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = fields.get(11)?.parse::<f64>().ok()? + fields.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

pub(crate) fn run(tools: &Tools) -> Option<String> {
    // absolute: the scene written below names its files from its own folder
    let root = &tools.root.canonicalize().ok()?;
    let Some(rings) = rings(root) else {
        eprintln!("gds_scale: examples/data/layout-paper-lens.csv not found (cargo xtask data)");
        return None;
    };
    let dir = root.join("target/gds-scale");
    std::fs::create_dir_all(&dir).ok()?;
    let gds = dir.join("paper-lens.gds");
    let t = Instant::now();
    let pillars = write(&gds, &rings, RADIUS_NM * fraction()).ok()?;
    let written = t.elapsed().as_secs_f64();
    let bytes = std::fs::metadata(&gds).ok()?.len();
    eprintln!("gds_scale: wrote {pillars} pillars, {bytes} bytes in {written:.1} s");
    let example = root.join("examples/library.toml");
    let library = root.join("examples/data/library-tio2-like.csv");
    let scene_text = std::fs::read_to_string(&example)
        .ok()?
        .replace(
            "layout = \"data/layout-paper-lens.csv\"",
            &format!("layout_gds = \"{}\"\ngds_layer = 1\nlattice_pitch_um = 0.4", gds.display()),
        )
        .replace("\"data/library-tio2-like.csv\"", &format!("\"{}\"", library.display()))
        .replace("focal_length_mm = 3.36", &format!("focal_length_mm = {}", 3.36 * fraction()));
    let scene_file = dir.join("scene.toml");
    std::fs::write(&scene_file, &scene_text).ok()?;
    let load_start = super::load_average();
    let cpu_start = cpu_seconds().unwrap_or(f64::NAN);
    let t = Instant::now();
    let options = scene::gds::GdsOptions {
        cell: None,
        layer: 1,
        datatype: 0,
        pitch_m: 400e-9,
        atom: scene::gds::AtomKind::Pillar,
        max_atoms: 1 << 26,
        max_sites: 1 << 26,
    };
    let grid = match scene::gds::read_layout(&gds, &options) {
        Ok(g) => g,
        Err(e) => {
            eprintln!("gds_scale: {e}");
            return None;
        }
    };
    let parse = t.elapsed().as_secs_f64();
    let cpu_parse = cpu_seconds().unwrap_or(f64::NAN) - cpu_start;
    let stats = grid.stats.clone();
    drop(grid);
    let t = Instant::now();
    let loaded = scene::load(Some(&scene_file), &[]);
    std::fs::remove_file(&scene_file).ok();
    let scene = match loaded {
        Ok(s) => s,
        Err(e) => {
            eprintln!("gds_scale: {e}");
            return None;
        }
    };
    let load = t.elapsed().as_secs_f64();
    // the evaluation's own CPU time, and the share of it spent building the pupil maps (the
    // FFT engine's field accumulator, summed over threads); the rest is the OTFs and the mean
    let cpu_eval_start = cpu_seconds().unwrap_or(f64::NAN);
    let field_start = optics::map::field_build_time();
    let t = Instant::now();
    let drawn = match metric::evaluate(&scene) {
        Ok(d) => d,
        Err(e) => {
            eprintln!("gds_scale: the drawn lens: {e}");
            return None;
        }
    };
    let evaluate = t.elapsed().as_secs_f64();
    let field_cpu = (optics::map::field_build_time() - field_start).as_secs_f64();
    let cpu_eval = cpu_seconds().unwrap_or(f64::NAN) - cpu_eval_start;
    let otf_cpu = cpu_eval - field_cpu;
    let peak = peak_gib().unwrap_or(f64::NAN);
    let cpu = cpu_seconds().unwrap_or(f64::NAN) - cpu_start;
    let cpu_total = cpu - cpu_parse;
    let load_end = super::load_average();
    drop(scene);
    let radial = match scene::load(Some(&example), &[])
        .map_err(|e| e.to_string())
        .and_then(|s| metric::evaluate(&s).map_err(|e| e.to_string()))
    {
        Ok(r) => r,
        Err(e) => {
            eprintln!("gds_scale: the radial lens: {e}");
            return None;
        }
    };
    std::fs::remove_file(&gds).ok();
    let total = load + evaluate;
    Some(format!(
        "## GDS layout at scale\n\n\
         `examples/library.toml`'s lens (the paper's aperture, 1.344 mm, F/2.5, on a 400 nm lattice) drawn as a GDSII \
         layout of 9-vertex pillars on a 1 nm grid (written by `cargo xtask accuracy --only gds_scale` into \
         `target/gds-scale/`, {written:.0} s, then deleted), read (`scene::gds`, streamed) and evaluated as the 2-D \
         library lens (`lens.layout_gds`: the layout held as a site map, each pupil sample the mean of its cells; \
         docs/physics.md, \"Resampling a layout to the pupil grid\") by the release build, one process; the target \
         is 60 s and 6 GB on a 2-core machine. The times are wall times on the machine as loaded (its load average beside them); the CPU \
         time is the process's own work; the evaluation's CPU time is split into building the pupil maps (the \
         field: the sites resampled to each wavelength's pupil grid, timed inside `optics::map::MapPupil::field` \
         and summed over threads, `optics::map::field_build_time`) and the rest (the FFTs, OTFs and mean MTF).\n\n\
         | pillars | GDS | records | parse alone | scene load (parse + lens) | evaluation (maps, OTFs) | evaluation's CPU: maps (field), OTFs and mean | load + evaluation | CPU time: parse alone, load + evaluation | peak memory | load average (start → end) |\n\
         |---|---|---|---|---|---|---|---|---|---|---|\n\
         | {pillars} | {:.2} GB | {} | {parse:.1} s | {load:.1} s | {evaluate:.1} s | {field_cpu:.1} s, {otf_cpu:.1} s | {total:.1} s | {cpu_parse:.1} s, {cpu_total:.1} s | {peak:.2} GiB | {load_start} → {load_end} |\n\n\
         As drawn: ASNR {:.3}, mean MTF {:.4}; the radial library lens of the same layout (`examples/library.toml`): \
         ASNR {:.3}, mean MTF {:.4} ({:+.2} % in ASNR; docs/physics.md, \"2-D library layouts\", states the lattice \
         error). Largest off-lattice distance {:.2} nm, {} doubly occupied sites.\n",
        bytes as f64 / 1e9,
        stats.records,
        drawn.asnr,
        drawn.mean_mtf,
        radial.asnr,
        radial.mean_mtf,
        100.0 * (drawn.asnr / radial.asnr - 1.0),
        stats.max_off_lattice_m * 1e9,
        stats.doubly_occupied_sites,
    ))
}
