//! `asnr sfr` end to end: the table, `--json` and `--csv` of one slanted edge agree with each
//! other, and bad input fails with the file and the reason (exit 1, no panic). The e-SFR's
//! accuracy against exact edges is `imaging`'s tests' (imaging/tests/sfr.rs); here the edges
//! only need to be edges.

mod common;

use std::path::{Path, PathBuf};

use common::{asnr, fails, json, stderr};

/// A fresh folder for one test's files.
fn folder(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("asnr-cli-sfr-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The level at `(x, y)` of a dark-to-bright step through `(x0, y0)` at `theta_deg` off
/// vertical, smoothed over about half a pixel.
fn step(x: f64, y: f64, x0: f64, y0: f64, theta_deg: f64) -> f64 {
    let t = theta_deg.to_radians();
    let n = (x - x0) * t.cos() - (y - y0) * t.sin();
    1.0 / (1.0 + (-n / 0.4).exp())
}

/// A `width × height` frame of `profile` averaged over 8 × 8 points of each pixel, scaled from
/// `dark` to `bright` and rounded to whole codes (clipped at `max`).
fn frame(width: usize, height: usize, dark: f64, bright: f64, max: f64, profile: impl Fn(f64, f64) -> f64) -> Vec<u16> {
    let mut levels = Vec::with_capacity(width * height);
    for j in 0..height {
        for i in 0..width {
            let mut sum = 0.0;
            for a in 0..8 {
                for b in 0..8 {
                    sum += profile(i as f64 - 0.5 + (a as f64 + 0.5) / 8.0, j as f64 - 0.5 + (b as f64 + 0.5) / 8.0);
                }
            }
            levels.push((dark + (bright - dark) * sum / 64.0).round().min(max) as u16);
        }
    }
    levels
}

/// A 16-bit PNG of an edge at `angle` degrees through the frame's middle.
fn edge_png(path: &Path, size: usize, angle: f64) {
    let c = size as f64 / 2.0 + 0.3;
    let levels = frame(size, size, 2000.0, 40000.0, 65535.0, |x, y| step(x, y, c, c, angle));
    imaging::write_png(path, size, size, &levels, 16).unwrap();
}

fn text(path: &Path) -> &str {
    path.to_str().unwrap()
}

#[test]
fn the_table_json_and_csv_of_one_edge_agree() {
    let dir = folder("one");
    let edge = dir.join("edge.png");
    edge_png(&edge, 96, 5.0);

    let value = json(&["sfr", text(&edge), "--json", "--pixel-pitch-um", "2"]);
    let mean = value["mean_mtf"].as_f64().unwrap();
    let angle = value["edge_angle_deg"].as_f64().unwrap();
    assert!(mean > 0.3 && mean < 1.0, "mean MTF {mean}");
    assert!((angle.abs() - 5.0).abs() < 0.1, "angle {angle}");
    assert!(value["mtf_nyquist"].as_f64().unwrap() < mean);
    assert!(value["mtf50_cyc_per_px"].as_f64().unwrap() > 0.0);
    assert_eq!(value["edges"].as_array().unwrap().len(), 1);
    let f: Vec<f64> = value["frequency_cyc_per_px"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    let mtf: Vec<f64> = value["mtf"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    assert_eq!(f.len(), mtf.len());
    assert!(f.iter().any(|f| (f - 0.5).abs() < 1e-12), "Nyquist is one of the frequencies");
    assert!((mtf[0] - 1.0).abs() < 1e-9, "normalized at 0: {}", mtf[0]);
    // 2 µm pixels: 500 cycles/mm per cycle/pixel
    let per_mm = value["frequency_cyc_per_mm"].as_array().unwrap();
    assert!((per_mm[10].as_f64().unwrap() - 500.0 * f[10]).abs() < 1e-9);

    // --csv: one row per frequency, the JSON's numbers
    let out = asnr(&["sfr", text(&edge), "--csv"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let csv = String::from_utf8(out.stdout).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("edge,frequency_cyc_per_px,mtf,mtf_sigma"));
    let rows: Vec<Vec<f64>> = lines.map(|l| l.split(',').map(|v| v.parse().unwrap()).collect()).collect();
    assert_eq!(rows.len(), mtf.len());
    for (row, (f, m)) in rows.iter().zip(f.iter().zip(&mtf)) {
        // the same decimals (serde_json's reader may round the last bit differently)
        assert_eq!(row[0], 1.0);
        assert!((row[1] - f).abs() <= 1e-15 && (row[2] - m).abs() <= 1e-15, "{row:?} vs {f}, {m}");
        assert!(row[3] >= 0.0);
    }

    // the table: the same mean MTF, angle and standard errors' origin
    let out = asnr(&["sfr", text(&edge)]);
    assert!(out.status.success(), "{}", stderr(&out));
    let table = String::from_utf8(out.stdout).unwrap();
    let line = table.lines().find(|l| l.starts_with("mean MTF")).unwrap();
    let printed: f64 = line.split_whitespace().nth(2).unwrap().parse().unwrap();
    assert!((printed - mean).abs() <= 5e-6, "{line} vs {mean}");
    assert!(table.contains(&format!("{angle:+.3}°")), "{table}");
    assert!(table.contains("MTF at Nyquist") && table.contains("ESF bins' scatter (one frame)"), "{table}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_stack_gives_standard_errors_from_its_spread() {
    let dir = folder("stack");
    let (a, b) = (dir.join("a.png"), dir.join("b.png"));
    edge_png(&a, 96, 5.0);
    let c = 96.0 / 2.0 + 0.3;
    // the second frame: the same edge a little brighter, so the frames differ
    let levels = frame(96, 96, 2100.0, 40500.0, 65535.0, |x, y| step(x, y, c, c, 5.0));
    imaging::write_png(&b, 96, 96, &levels, 16).unwrap();
    let value = json(&["sfr", text(&a), text(&b), "--json"]);
    assert_eq!(value["frames"].as_u64(), Some(2));
    assert_eq!(value["uncertainty"].as_str(), Some("frames"), "{value}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn bad_input_fails_with_the_file_and_the_reason() {
    let dir = folder("bad");
    let size = 96;
    let c = size as f64 / 2.0 + 0.3;
    let write = |name: &str, levels: &[u16], size: usize| {
        let path = dir.join(name);
        imaging::write_png(&path, size, size, levels, 16).unwrap();
        path
    };

    // no edge: a flat frame with a little structure
    let flat: Vec<u16> = (0..size * size).map(|p| 1000 + (p * 7919 % 13) as u16).collect();
    let path = write("flat.png", &flat, size);
    let e = fails(&["sfr", text(&path)]);
    assert!(e.contains("flat.png") && e.contains("no edge"), "{e}");

    // two edges: a bright bar 40 pixels wide
    let bar =
        frame(size, size, 2000.0, 40000.0, 65535.0, |x, y| step(x, y, c - 20.0, c, 5.0) - step(x, y, c + 20.0, c, 5.0));
    let path = write("bar.png", &bar, size);
    // `asnr sfr` reports both; the measured ASNR needs one and says so
    let value = json(&["sfr", text(&path), "--json"]);
    assert_eq!(value["edges"].as_array().unwrap().len(), 2, "{value}");
    // a stack to measure the SNR from: two frames of the bar with a pattern of noise that grows
    // with the level (the bright bar noisier than the dark sides, as shot noise is)
    let noisy = |k: usize| -> Vec<u16> {
        bar.iter().enumerate().map(|(p, &v)| v + ((p * 31 + k * 17) % 7) as u16 * (v / 2000)).collect()
    };
    let stack = [write("s0.png", &noisy(0), size), write("s1.png", &noisy(1), size)];
    let e = fails(&[
        "measure",
        text(&stack[0]),
        text(&stack[1]),
        "--white",
        "44,40,8,8",
        "--black",
        "4,40,8,8",
        "--edge",
        text(&path),
    ]);
    assert!(e.contains("2 edges") && e.contains("give a ROI around one"), "{e}");

    // edges at 0° and 45°: outside ISO 12233's range, the angle named
    for (angle, name, word) in [(0.0, "zero.png", "0.00°"), (45.0, "diagonal.png", "45.00°")] {
        let levels = frame(size, size, 2000.0, 40000.0, 65535.0, |x, y| step(x, y, c, c, angle));
        let path = write(name, &levels, size);
        let e = fails(&["sfr", text(&path)]);
        assert!(e.contains(word) && e.contains("ISO 12233") && e.contains(name), "{angle}°: {e}");
    }

    // saturated: the bright side clipped at the 16-bit code 65535
    let clipped = frame(size, size, 10000.0, 80000.0, 65535.0, |x, y| step(x, y, c, c, 5.0));
    let path = write("saturated.png", &clipped, size);
    let e = fails(&["sfr", text(&path)]);
    assert!(e.contains("saturated") && e.contains("saturated.png") && e.contains('%'), "{e}");

    // frames of different sizes
    let edge = dir.join("edge.png");
    edge_png(&edge, size, 5.0);
    let small = dir.join("small.png");
    edge_png(&small, 64, 5.0);
    let e = fails(&["sfr", text(&edge), text(&small)]);
    assert!(e.contains("small.png") && e.contains("edge.png") && e.contains("64 × 64"), "{e}");

    // a ROI outside the frame
    let e = fails(&["sfr", text(&edge), "--roi", "50,0,60,40"]);
    assert!(e.contains("ROI") && e.contains("outside") && e.contains("96 × 96"), "{e}");

    // a 16-bit PNG whose header claims 10⁶ × 10⁶ pixels, and nothing after: refused from the
    // header (decoding would allocate 2 TB first)
    let huge = dir.join("huge.png");
    let mut bytes = b"\x89PNG\r\n\x1a\n\x00\x00\x00\x0dIHDR".to_vec();
    bytes.extend(1_000_000_u32.to_be_bytes());
    bytes.extend(1_000_000_u32.to_be_bytes());
    bytes.extend([16, 0, 0, 0, 0, 0, 0, 0, 0]);
    std::fs::write(&huge, bytes).unwrap();
    let e = fails(&["sfr", text(&huge)]);
    assert!(e.contains("huge.png") && e.contains("1000000"), "{e}");

    // a file that is not there
    let e = fails(&["sfr", text(&dir.join("missing.png"))]);
    assert!(e.contains("missing.png"), "{e}");
    std::fs::remove_dir_all(dir).unwrap();
}

/// The ROI's edges each reported when they stand apart, refused when they cannot be taken apart.
/// Several edges well apart (a bright bar 40 pixels wide: two edges 40 pixels apart along their
/// normal, more than the 8 pixels two ESFs need) give one entry each in the table, `--json`'s
/// `edges` and the CSV's `edge` column, each edge's MTF the same within the ESF's bins (the two
/// edges are mirror images of one blur); two edges 5 pixels apart, a corner where two edges
/// cross, and two near-vertical edges crossing in an X are refused, naming the ROI and where
/// the edges are; `asnr measure --edge` refuses two edges it could tell apart, naming the option
/// that picks one.
#[test]
fn each_separate_edge_is_reported_and_edges_that_cannot_be_separated_are_refused() {
    let dir = folder("two");
    let size = 96;
    let c = size as f64 / 2.0 + 0.3;
    let write = |name: &str, levels: &[u16]| {
        let path = dir.join(name);
        imaging::write_png(&path, size, size, levels, 16).unwrap();
        path
    };

    // a bar 40 pixels wide: both edges, each with its own MTF
    let bar =
        frame(size, size, 2000.0, 40000.0, 65535.0, |x, y| step(x, y, c - 20.0, c, 5.0) - step(x, y, c + 20.0, c, 5.0));
    let path = write("bar.png", &bar);
    let value = json(&["sfr", text(&path), "--json"]);
    let edges = value["edges"].as_array().unwrap();
    assert_eq!(edges.len(), 2, "{value}");
    let column = |e: &serde_json::Value| e["centre_px"][0].as_f64().unwrap();
    assert!((column(&edges[0]) - (c - 20.0)).abs() < 1.0 && (column(&edges[1]) - (c + 20.0)).abs() < 1.0, "{value}");
    let means: Vec<f64> = edges.iter().map(|e| e["mean_mtf"].as_f64().unwrap()).collect();
    assert!((means[0] - means[1]).abs() < 0.01 * means[0], "mirror-image edges: {means:?}");
    // the CSV: every frequency of edge 1, then of edge 2
    let out = asnr(&["sfr", text(&path), "--csv"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let csv = String::from_utf8(out.stdout).unwrap();
    let per_edge = edges[0]["mtf"].as_array().unwrap().len();
    for k in ["1", "2"] {
        assert_eq!(csv.lines().skip(1).filter(|l| l.split(',').next() == Some(k)).count(), per_edge, "{csv}");
    }
    // the table: one block per edge
    let out = asnr(&["sfr", text(&path)]);
    let table = String::from_utf8(out.stdout).unwrap();
    assert!(table.contains("edge 1") && table.contains("edge 2"), "{table}");

    // the measured ASNR needs one edge's MTF: refused, the option that picks one named
    let noisy = |k: usize| -> Vec<u16> {
        bar.iter().enumerate().map(|(p, &v)| v + ((p * 31 + k * 17) % 7) as u16 * (v / 2000)).collect()
    };
    let stack = [write("s0.png", &noisy(0)), write("s1.png", &noisy(1))];
    let measure = |extra: &[&str]| {
        let mut args = vec!["measure", text(&stack[0]), text(&stack[1]), "--white", "44,40,8,8", "--black", "4,40,8,8"];
        args.extend_from_slice(extra);
        args.iter().map(|s| s.to_string()).collect::<Vec<String>>()
    };
    let args = measure(&["--edge", text(&path)]);
    let e = fails(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(e.contains("2 edges") && e.contains("--edge-roi") && e.contains("ROI 0,0,96,96"), "{e}");
    // ... and with --edge-roi around the left edge it measures
    let args = measure(&["--edge", text(&path), "--edge-roi", "8,0,48,96"]);
    let out = asnr(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(out.status.success(), "{}", stderr(&out));

    // a bar 5 pixels wide: its two edges closer than two ESFs allow
    let narrow =
        frame(size, size, 2000.0, 40000.0, 65535.0, |x, y| step(x, y, c - 2.5, c, 5.0) - step(x, y, c + 2.5, c, 5.0));
    let path = write("narrow.png", &narrow);
    let e = fails(&["sfr", text(&path)]);
    assert!(e.contains("narrow.png") && e.contains("ROI 0,0,96,96") && e.contains("--roi"), "{e}");
    assert!(e.contains("column ") && e.contains(", row "), "where: {e}");

    // a corner of four quadrants, bright where the two edges' steps agree: the edges cross
    let corner = frame(size, size, 2000.0, 40000.0, 65535.0, |x, y| {
        let (v, h) = (step(x, y, c, c, 5.0), step(y, x, c, c, -5.0));
        v * h + (1.0 - v) * (1.0 - h)
    });
    let path = write("corner.png", &corner);
    let e = fails(&["sfr", text(&path)]);
    assert!(e.contains("corner.png") && e.contains("cross") && e.contains(", row "), "{e}");

    // two near-vertical edges crossing in an X: bright between them above and below the crossing
    let x = frame(size, size, 2000.0, 40000.0, 65535.0, |x, y| {
        let (a, b) = (step(x, y, c, c, 8.0), step(x, y, c, c, -8.0));
        a + b - 2.0 * a * b
    });
    let path = write("x.png", &x);
    let e = fails(&["sfr", text(&path)]);
    assert!(e.contains("x.png") && e.contains("cross") && e.contains("--roi"), "{e}");
    std::fs::remove_dir_all(dir).unwrap();
}
