//! The radial engine (`optics::radial`) against references written here: the exact defocused
//! OTF, a brute-force autocorrelation over the overlap in polar coordinates about its midpoint
//! (another parametrization, Gauss–Legendre in both directions, many panels), and the FFT of the
//! sampled pupil (`monochromatic_mtf` through the FFT layer).

use std::sync::Arc;

use optics::radial::{RadialOrder, RadialProfile, RadialPupil};
use optics::{Field, LensModel, Order, Pupil, Wavefront, defocus_otf, monochromatic_mtf};

const LAMBDA: f64 = 800e-9;

/// The OTF at `s` of the pupil field `amp(q) exp(i 2π w(q)/λ)` (`q = ρ²`) by brute force: the
/// overlap of the two unit discs centred at `±s` (shift `d = 2s`), in polar coordinates `(r, θ)`
/// about the midpoint, `θ ∈ [−π/2, π/2]` (the half `x > 0`, doubled as `2 Re`), `r` up to the
/// edge of the disc at `−s`, `r_max = −s cos θ + √(1 − s² sin²θ)`: 24 × 16 Gauss–Legendre
/// points in each direction.
fn brute_force(s: f64, amp: &dyn Fn(f64) -> f64, w: &dyn Fn(f64) -> f64) -> f64 {
    let rule = optics::quad::gauss_legendre(16);
    let panels = 24;
    let k = std::f64::consts::TAU / LAMBDA;
    let mut sum = 0.0;
    let half = std::f64::consts::FRAC_PI_2;
    for pt in 0..panels {
        let (a, b) =
            (-half + 2.0 * half * pt as f64 / panels as f64, -half + 2.0 * half * (pt + 1) as f64 / panels as f64);
        for &(xt, wt) in &rule {
            let theta = 0.5 * (a + b) + 0.5 * (b - a) * xt;
            let (st, ct) = theta.sin_cos();
            let r_max = -s * ct + (1.0 - s * s * st * st).sqrt();
            for pr in 0..panels {
                let (ra, rb) = (r_max * pr as f64 / panels as f64, r_max * (pr + 1) as f64 / panels as f64);
                for &(xr, wr) in &rule {
                    let r = 0.5 * (ra + rb) + 0.5 * (rb - ra) * xr;
                    let (x, y) = (r * ct, r * st);
                    let q1 = (x + s) * (x + s) + y * y;
                    let q2 = (x - s) * (x - s) + y * y;
                    let value = amp(q1) * amp(q2) * (k * (w(q1) - w(q2))).cos();
                    sum += 0.25 * (b - a) * wt * (rb - ra) * wr * r * value;
                }
            }
        }
    }
    // power: π ∫_0^1 amp(q)² dq, by 64 × 16 points
    let mut power = 0.0;
    for p in 0..64 {
        for &(x, w) in &rule {
            let q = (p as f64 + 0.5 + 0.5 * x) / 64.0;
            power += 0.5 * w / 64.0 * amp(q) * amp(q);
        }
    }
    2.0 * sum / (std::f64::consts::PI * power)
}

fn order_of(pupil: RadialPupil, w020: f64) -> RadialOrder {
    let pupil = Arc::new(pupil);
    let w = w020 + pupil.fitted_defocus_m();
    RadialOrder::new(pupil, w, LAMBDA)
}

/// A pupil with no terms is the defocused circle: against `defocus_otf` (exact to rounding).
#[test]
fn plain_defocus_matches_the_exact_otf() {
    for &w in &[0.0, 0.25, 1.0, 3.0] {
        let order = order_of(RadialPupil::default(), w * LAMBDA);
        for i in 1..20 {
            let s = i as f64 / 20.0;
            let (got, want) = (order.otf(s, 1e-12), defocus_otf(s, w));
            assert!((got - want).abs() < 1e-11, "s = {s}, w = {w}: {got} vs {want}");
        }
    }
}

/// Defocus given as a profile term (an even polynomial, a table), with its fit moved into the
/// order: the same OTF.
#[test]
fn defocus_as_a_profile_term_matches() {
    let w = 1.5 * LAMBDA;
    let poly = Arc::new(RadialProfile::even_polynomial(vec![0.3, 1.0]).unwrap());
    let pupil = RadialPupil::new(None, vec![(w, poly.clone())], vec![]).unwrap();
    assert!((pupil.fitted_defocus_m() - w).abs() < 1e-20);
    let order = order_of(pupil, 0.0);
    for i in 1..10 {
        let s = i as f64 / 10.0;
        let (got, want) = (order.otf(s, 1e-12), defocus_otf(s, 1.5));
        assert!((got - want).abs() < 1e-11, "s = {s}: {got} vs {want}");
    }
}

/// Spherical aberration (−0.84 waves at the rim, the quadratic phase's at the paper's aperture)
/// and an amplitude apodization against the brute-force autocorrelation.
#[test]
fn spherical_and_apodized_pupils_match_the_brute_force_integral() {
    let w040 = -0.84 * LAMBDA;
    let quartic = Arc::new(RadialProfile::even_polynomial(vec![0.0, 0.0, 1.0]).unwrap());
    let gauss: Vec<f64> = (0..=60).map(|i| i as f64 / 60.0).collect();
    let amp_values: Vec<f64> = gauss.iter().map(|r| (-0.7 * r * r).exp()).collect();
    let amplitude = Arc::new(RadialProfile::table(gauss, amp_values).unwrap());
    for (apodized, w020) in [(false, 0.0), (false, 0.6 * LAMBDA), (true, -0.4 * LAMBDA)] {
        let amp_profile = apodized.then(|| amplitude.clone());
        let pupil = RadialPupil::new(amp_profile.clone(), vec![(w040, quartic.clone())], vec![]).unwrap();
        let order = order_of(pupil, w020);
        let amp = |q: f64| amp_profile.as_ref().map_or(1.0, |a| a.value(q));
        let wf = |q: f64| w020 * q + w040 * q * q;
        for &s in &[0.05, 0.2, 0.37, 0.6, 0.9] {
            let (got, want) = (order.otf(s, 1e-12), brute_force(s, &amp, &wf));
            assert!((got - want).abs() < 1e-9, "apodized {apodized}, W020 {w020}, s = {s}: {got} vs {want}");
        }
    }
}

/// Z11 on a radial pupil against its Seidel equivalent, `c Z11 = √5 c (6ρ⁴ − 6ρ² + 1)`:
/// `W040 = 6√5 c`, `W020 = −6√5 c`, through the brute-force integral (the piston drops out).
#[test]
fn zernike_z11_is_its_seidel_equivalent() {
    let c = 0.1e-6;
    let pupil = RadialPupil::new(None, vec![], vec![(11, c)]).unwrap();
    let order = order_of(pupil, 0.0);
    let r5 = 5f64.sqrt();
    let wf = |q: f64| 6.0 * r5 * c * q * q - 6.0 * r5 * c * q;
    for &s in &[0.1, 0.3, 0.5, 0.8] {
        let (got, want) = (order.otf(s, 1e-12), brute_force(s, &|_| 1.0, &wf));
        assert!((got - want).abs() < 1e-9, "s = {s}: {got} vs {want}");
    }
}

/// One order through a radial pupil, for `monochromatic_mtf`.
#[derive(Debug)]
struct OneOrder(Arc<RadialPupil>, f64);

impl LensModel for OneOrder {
    fn f_number(&self) -> f64 {
        2.5
    }
    fn focal_length(&self) -> f64 {
        3.36e-3
    }
    fn orders(&self, _: f64, _: Field) -> Vec<Order> {
        vec![Order::radial(0.5, self.0.clone(), Wavefront::defocus(self.1))]
    }
}

/// The radial engine against the FFT of the sampled pupil (`monochromatic_mtf`; a vanishing
/// coma-like Zernike term, 1e-15 m, sends the order to the FFT layer): spherical aberration with
/// an apodization, at 512 samples across the pupil (the FFT path's error ~1e-4).
#[test]
fn radial_engine_matches_the_fft_of_the_sampled_pupil() {
    let quartic = Arc::new(RadialProfile::even_polynomial(vec![0.0, 0.0, 1.0]).unwrap());
    let r: Vec<f64> = (0..=40).map(|i| i as f64 / 40.0).collect();
    let a: Vec<f64> = r.iter().map(|r| 1.0 - 0.5 * r * r).collect();
    let amplitude = Arc::new(RadialProfile::table(r, a).unwrap());
    let terms = vec![(-0.5 * LAMBDA, quartic)];
    let symmetric = Arc::new(RadialPupil::new(Some(amplitude.clone()), terms.clone(), vec![]).unwrap());
    let nudged = Arc::new(RadialPupil::new(Some(amplitude), terms, vec![(7, 1e-15)]).unwrap());
    let f_cut = 1.0 / (LAMBDA * 2.5);
    let freqs: Vec<f64> = (1..10).map(|i| i as f64 / 10.0 * f_cut).collect();
    let exact = monochromatic_mtf(&OneOrder(symmetric, 0.3 * LAMBDA), LAMBDA, Field::ON_AXIS, &freqs, 64).unwrap();
    let fft = monochromatic_mtf(&OneOrder(nudged, 0.3 * LAMBDA), LAMBDA, Field::ON_AXIS, &freqs, 512).unwrap();
    for ((e, f), nu) in exact.iter().zip(&fft).zip(&freqs) {
        assert!((e - f).abs() < 1e-3, "ν = {nu}: radial {e} vs FFT {f}");
    }
    // and the radial engine is what the exact path used
    assert!(matches!(
        OneOrder(Arc::new(RadialPupil::default()), 0.0).orders(LAMBDA, Field::ON_AXIS)[0].pupil,
        Pupil::Radial(_)
    ));
}

/// The accuracy asked drives the work: at 1e-6 the value is within 1e-6 of the 1e-13 one, on
/// a strongly aberrated pupil (6 waves of defocus, 2 of spherical).
#[test]
fn looser_accuracy_stays_within_itself() {
    let quartic = Arc::new(RadialProfile::even_polynomial(vec![0.0, 0.0, 1.0]).unwrap());
    let pupil = RadialPupil::new(None, vec![(2.0 * LAMBDA, quartic)], vec![]).unwrap();
    let order = order_of(pupil, 6.0 * LAMBDA);
    for i in 1..20 {
        let s = i as f64 / 20.0;
        let (loose, tight) = (order.otf(s, 1e-6), order.otf(s, 1e-13));
        assert!((loose - tight).abs() < 1e-6, "s = {s}: {loose} vs {tight}");
    }
}
