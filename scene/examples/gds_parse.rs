//! The GDSII reader's speed: writes a flat layout of N × N 9-vertex pillars (default N = 1000,
//! 10⁶ pillars, about 170 MB) on a 400 nm lattice to a temporary file, reads it back into the
//! atom grid, and prints records/s, MB/s and the peak resident memory (Linux).
//!
//! `cargo run --release -p asnr-scene --example gds_parse [N]`

use std::io::BufWriter;
use std::time::Instant;

use scene::gds::{AtomKind, GdsOptions, Writer, read_layout};

fn peak_rss_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024.0)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let n: usize = std::env::args().nth(1).map_or(Ok(1000), |a| a.parse())?;
    let path = std::env::temp_dir().join(format!("asnr-gds-bench-{}.gds", std::process::id()));
    let pitch = 400; // nm, database unit 1 nm
    let start = Instant::now();
    {
        let mut w = Writer::new(BufWriter::new(std::fs::File::create(&path)?), 1e-9)?;
        w.begin_cell("TOP")?;
        for j in 0..n {
            for i in 0..n {
                let d = 100.0 + 200.0 * ((i * 7 + j * 13) % 97) as f64 / 97.0;
                let c = ((i * pitch) as f64, (j * pitch) as f64);
                let vertices: Vec<(i32, i32)> = (0..9)
                    .map(|k| {
                        let a = std::f64::consts::TAU * k as f64 / 9.0;
                        ((c.0 + 0.5 * d * a.cos()).round() as i32, (c.1 + 0.5 * d * a.sin()).round() as i32)
                    })
                    .collect();
                w.polygon(1, 0, &vertices)?;
            }
        }
        w.end_cell()?;
        std::io::Write::flush(&mut w.finish()?)?;
    }
    let written = start.elapsed().as_secs_f64();
    let bytes = std::fs::metadata(&path)?.len();
    let o = GdsOptions {
        cell: None,
        layer: 1,
        datatype: 0,
        pitch_m: 400e-9,
        atom: AtomKind::Pillar,
        max_atoms: 1 << 32,
        max_sites: 1 << 32,
    };
    let start = Instant::now();
    let grid = read_layout(&path, &o)?;
    let read = start.elapsed().as_secs_f64();
    std::fs::remove_file(&path).ok();
    let s = &grid.stats;
    println!("pillars            {}", s.atoms);
    println!("file               {:.1} MB (written in {written:.2} s)", bytes as f64 / 1e6);
    println!("records            {}", s.records);
    println!("read + grid        {read:.3} s");
    println!("records/s          {:.3e}", s.records as f64 / read);
    println!("MB/s               {:.1}", bytes as f64 / 1e6 / read);
    println!(
        "grid               {} × {}, {} empty, largest off-lattice {:.2} nm",
        grid.nx,
        grid.ny,
        s.empty_sites,
        s.max_off_lattice_m * 1e9
    );
    println!("diameters          {:.1} to {:.1} nm", s.parameter_range[0].0, s.parameter_range[0].1);
    if let Some(m) = peak_rss_mib() {
        println!("peak RSS           {m:.0} MiB");
    }
    Ok(())
}
