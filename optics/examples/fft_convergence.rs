//! Regenerates the convergence table of the `optics::fft` module docs: the error of the FFT
//! path's mean MTF over [0, 0.2] against the exact 1-D path, per pupil sampling.
//!
//! `cargo run -p asnr-optics --example fft_convergence`

fn main() {
    let sizes = [32, 64, 128, 256, 512, 1024];
    let w0 = optics::fft::convergence_table(0.0, 0.2, &sizes);
    let w1 = optics::fft::convergence_table(1.0, 0.2, &sizes);
    println!("| N | M | error, w = 0 | error, w = 1 | time per evaluation |");
    println!("|---|---|---|---|---|");
    for ((n, e0, t0), (_, e1, t1)) in w0.into_iter().zip(w1) {
        let m = optics::fft::OtfPlan::new(n, 0.2).map(|p| p.padded_len()).unwrap_or(0);
        println!("| {n} | {m} | {e0:.1e} | {e1:.1e} | {:.2} ms |", 1e3 * t0.min(t1));
    }
}
