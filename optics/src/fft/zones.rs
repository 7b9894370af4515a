//! A composite pupil of coherent zones: several apertures of one lens, each with its own
//! amplitude and wavefront, sampled once on the full aperture's grid.
//!
//! docs/physics.md, "General pupils": the OTF is the normalized autocorrelation of the pupil
//! field. The zones of one aperture at one wavelength are coherent (a segmented spatially
//! multiplexed lens is one lens, its segments' fields add), so the field of pixel `k` is
//!
//! ```text
//! P_k = Σ_j A_jk a_j exp(i 2π (W_j(x_k) + t_j · x_k)/λ)
//! ```
//!
//! with `A_jk` the exact area fraction of pixel `k` inside zone `j` (a boundary pixel shared by
//! two zones gets both parts: zones that tile the circle with one amplitude and wavefront give
//! the circle's pupil, pixel by pixel, to rounding), `a_j` the zone's field amplitude, `W_j` its
//! wavefront (full-aperture coordinates centred on the lens axis, the sign of docs/physics.md,
//! "Sign of the wavefront") and `t_j` a tilt (m of OPD at the edge of the full aperture). The
//! OTF is normalized by `Σ_k Σ_j A_jk a_j²`, the power the zones pass, which is the single
//! aperture's `Σ A` for one zone of amplitude 1 ([`OtfPlan::otf_of_field`](super::OtfPlan::otf_of_field)).
//!
//! Coordinates: the grid spans the full aperture `[-1, 1]²` (units of its radius `R`, centred
//! on the lens axis), pixel `(i, j)` as in [`SampledPupil`](super::SampledPupil). A zone's
//! aperture is placed on it at its [`decentre`](Aperture::decentre) (for a
//! [`ring`](Aperture::ring), none); what falls outside the grid is not sampled.
//!
//! A tilt `t = (Δx, Δy) NA` moves the zone's image by `Δ` on the detector (NA = 1/(2 F#)):
//! the stationary phase of the Fraunhofer integral (module docs of [`fft`](super)) puts the PSF
//! of `W = t x` at `x0 = t z/R = t/NA`, and its OTF carries `exp(−2πi ν·Δ)`, the phase an
//! order-level image shift gets (tested: one full-circle zone tilted by `Δ NA` against the
//! circle with the order's shift).

use std::f64::consts::TAU;
use std::sync::Arc;

use num_complex::Complex64;

use super::aperture::Aperture;
use super::wavefront::{Aberrations, Compiled};
use crate::Error;

/// One zone's field at one wavelength: its amplitude, wavefront and tilt.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ZoneField {
    /// Field amplitude `a_j ≥ 0` (the zone passes `a_j²` of the power incident on it).
    pub amplitude: f64,
    /// The zone's wavefront, full-aperture coordinates from the lens axis.
    pub aberrations: Aberrations,
    /// Tilt `(t_x, t_y)`, m of OPD at the full aperture's edge: `W += t_x x + t_y y`.
    pub tilt_m: [f64; 2],
}

/// The zones of a composite pupil sampled on an `N × N` grid over the full aperture (module
/// docs): each zone's pixels with their exact area fractions, kept while the apertures stay the
/// same, and the complex field at the last wavelength.
#[derive(Clone, Debug)]
pub struct SampledZones {
    n: usize,
    apertures: Vec<Arc<Aperture>>,
    /// per zone: (pixel index, area fraction in (0, 1])
    pixels: Vec<Vec<(usize, f64)>>,
    field: Vec<Complex64>,
    weight: f64,
}

impl SampledZones {
    /// Samples the zones `apertures` on an `n × n` grid (`n` in `8..=8192`), at least one zone.
    pub fn new(n: usize, apertures: &[Arc<Aperture>]) -> Result<SampledZones, Error> {
        super::plan::check_samples(n)?;
        if apertures.is_empty() {
            return Err(Error::InvalidParameter { name: "zones", value: 0.0, expected: "at least one zone" });
        }
        let h = 2.0 / n as f64;
        let pixels = apertures
            .iter()
            .map(|aperture| {
                let (dx, dy) = aperture.decentre();
                let mut list = Vec::new();
                for j in 0..n {
                    let y0 = -1.0 + j as f64 * h - dy;
                    for i in 0..n {
                        let x0 = -1.0 + i as f64 * h - dx;
                        let a = (aperture.area_in(x0, x0 + h, y0, y0 + h) / (h * h)).clamp(0.0, 1.0);
                        if a > 0.0 {
                            list.push((j * n + i, a));
                        }
                    }
                }
                list
            })
            .collect();
        Ok(SampledZones {
            n,
            apertures: apertures.to_vec(),
            pixels,
            field: vec![Complex64::new(0.0, 0.0); n * n],
            weight: 0.0,
        })
    }

    /// Whether these are the zones `apertures` (the same `Arc`s, in order): the sampling can be
    /// reused.
    pub fn is_sampling_of<'z>(&self, apertures: impl ExactSizeIterator<Item = &'z Arc<Aperture>>) -> bool {
        apertures.len() == self.apertures.len() && apertures.zip(&self.apertures).all(|(a, b)| Arc::ptr_eq(a, b))
    }

    /// Samples across the full aperture's diameter.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Zones sampled.
    pub fn len(&self) -> usize {
        self.apertures.len()
    }

    /// Whether there is no zone (never: [`new`](Self::new) refuses none).
    pub fn is_empty(&self) -> bool {
        self.apertures.is_empty()
    }

    /// The area of zone `j` on the grid, in units of `R²` (its exact area for the disc shapes,
    /// inside the grid).
    pub fn zone_area(&self, j: usize) -> f64 {
        let h = 2.0 / self.n as f64;
        self.pixels[j].iter().map(|&(_, a)| a).sum::<f64>() * h * h
    }

    /// Computes the composite field `Σ_j A_jk a_j exp(i 2π (W_j + t_j·x)/λ)` at `wavelength_m`
    /// for `zones` (one per sampled aperture, in order) and its weight `Σ_k Σ_j A_jk a_j²`.
    pub fn set_field(&mut self, zones: &[ZoneField], wavelength_m: f64) -> Result<(), Error> {
        if zones.len() != self.apertures.len() {
            return Err(Error::InvalidParameter {
                name: "zone fields",
                value: zones.len() as f64,
                expected: "one per sampled zone",
            });
        }
        if !(wavelength_m > 0.0 && wavelength_m.is_finite()) {
            return Err(Error::InvalidParameter {
                name: "wavelength",
                value: wavelength_m,
                expected: "finite and > 0 m",
            });
        }
        for z in zones {
            if !(z.amplitude.is_finite() && z.amplitude >= 0.0) {
                return Err(Error::InvalidParameter {
                    name: "zone amplitude",
                    value: z.amplitude,
                    expected: "finite and ≥ 0",
                });
            }
            z.aberrations.validate()?;
            if let Some(&t) = z.tilt_m.iter().find(|t| !t.is_finite()) {
                return Err(Error::InvalidParameter { name: "zone tilt", value: t, expected: "finite (m)" });
            }
        }
        let n = self.n;
        let h = 2.0 / n as f64;
        let k = TAU / wavelength_m;
        self.field.fill(Complex64::new(0.0, 0.0));
        let mut weight = 0.0;
        for (z, pixels) in zones.iter().zip(&self.pixels) {
            if z.amplitude == 0.0 {
                continue;
            }
            let compiled = Compiled::new(&z.aberrations);
            let [tx, ty] = z.tilt_m;
            let mut area = 0.0;
            for &(p, a) in pixels {
                let (i, j) = (p % n, p / n);
                let (x, y) = (-1.0 + (i as f64 + 0.5) * h, -1.0 + (j as f64 + 0.5) * h);
                let opd = compiled.opd_m(x, y) + tx * x + ty * y;
                self.field[p] += Complex64::from_polar(a * z.amplitude, k * opd);
                area += a;
            }
            weight += area * z.amplitude * z.amplitude;
        }
        self.weight = weight;
        Ok(())
    }

    /// The derivative of the composite field of [`set_field`](Self::set_field) (the same
    /// `zones` and `wavelength_m`) where each zone's amplitude moves by `d_amplitude[j]` and its
    /// OPD by `opd_rate(j, x, y)` (m per unit key at the pixel centre, full-aperture
    /// coordinates): `∂P_k = Σ_j A_jk (∂a_j + i k a_j ∂W_j(x_k)) exp(i k (W_j + t_j·x_k))`, and
    /// the weight's `Σ_k Σ_j 2 A_jk a_j ∂a_j` (docs/physics.md, "Gradients: the multiplexed
    /// lens"; a zone of amplitude 0 passes nothing and moves nothing). The same pixels, areas and
    /// phases as `set_field`. `None` where `zones` or `d_amplitude` is not one per sampled zone.
    pub fn field_derivative(
        &self,
        zones: &[ZoneField],
        wavelength_m: f64,
        d_amplitude: &[f64],
        opd_rate: &dyn Fn(usize, f64, f64) -> f64,
    ) -> Option<(Vec<Complex64>, f64)> {
        if zones.len() != self.apertures.len() || d_amplitude.len() != zones.len() {
            return None;
        }
        let n = self.n;
        let h = 2.0 / n as f64;
        let k = TAU / wavelength_m;
        let mut moved = vec![Complex64::new(0.0, 0.0); n * n];
        let mut d_weight = 0.0;
        for (zone, (z, pixels)) in zones.iter().zip(&self.pixels).enumerate() {
            if z.amplitude == 0.0 {
                continue;
            }
            let compiled = Compiled::new(&z.aberrations);
            let [tx, ty] = z.tilt_m;
            let da = d_amplitude[zone];
            let mut area = 0.0;
            for &(p, a) in pixels {
                let (i, j) = (p % n, p / n);
                let (x, y) = (-1.0 + (i as f64 + 0.5) * h, -1.0 + (j as f64 + 0.5) * h);
                let opd = compiled.opd_m(x, y) + tx * x + ty * y;
                let rate = Complex64::new(da, k * z.amplitude * opd_rate(zone, x, y));
                moved[p] += rate * Complex64::from_polar(a, k * opd);
                area += a;
            }
            d_weight += 2.0 * area * z.amplitude * da;
        }
        Some((moved, d_weight))
    }

    /// The derivative of the composite field of [`set_field`](Self::set_field) (the same
    /// `zones` and `wavelength_m`) where each zone moves at the lens's rates `rates` (one per
    /// sampled zone, per unit of a key, `LensModel::zone_rates`): its amplitude, its OPD
    /// `∂W_j = ∂W020_j (x² + y²) + NA ∂Δ_j·(x, y)` ([`field_derivative`](Self::field_derivative),
    /// `na` the NA), and its edges ([`ZoneRate::edges`](crate::ZoneRate::edges)): pixel `k`'s
    /// area fraction in zone `j` moves by `∂A_jk = Σ_e ∂e · (∂A_jk/∂e)`, each edge's rate of the
    /// pixel's exact area ([`Aperture::edge_rates_in`]: a circle's length, a radial edge's
    /// `∫ r dr`, over `h²`), so `∂P_k += Σ_j ∂A_jk a_j e^{ik(W_j + t_j·x_k)}` at the pixel's centre
    /// and the weight `Σ A a²` by `Σ ∂A a²` (docs/physics.md, "Gradients: the multiplexed lens").
    /// `None` where `zones` or `rates` is not one per sampled zone, or a zone whose edges move is
    /// a mask (its edges are not parameters).
    pub fn rates_derivative(
        &self,
        zones: &[ZoneField],
        wavelength_m: f64,
        rates: &[crate::ZoneRate],
        na: f64,
    ) -> Option<(Vec<Complex64>, f64)> {
        if rates.len() != self.apertures.len() {
            return None;
        }
        let d_amplitude: Vec<f64> = rates.iter().map(|r| r.amplitude).collect();
        let (mut moved, mut d_weight) = self.field_derivative(zones, wavelength_m, &d_amplitude, &|j, x, y| {
            let r = &rates[j];
            r.defocus_m * (x * x + y * y) + na * (r.image_shift_m[0] * x + r.image_shift_m[1] * y)
        })?;
        let n = self.n;
        let h = 2.0 / n as f64;
        let k = TAU / wavelength_m;
        for ((z, rate), aperture) in zones.iter().zip(rates).zip(&self.apertures) {
            if rate.edges == [0.0; 4] || z.amplitude == 0.0 {
                continue;
            }
            let compiled = Compiled::new(&z.aberrations);
            let [tx, ty] = z.tilt_m;
            let (dx, dy) = aperture.decentre();
            let mut d_area = 0.0;
            for j in 0..n {
                let y0 = -1.0 + j as f64 * h - dy;
                for i in 0..n {
                    let x0 = -1.0 + i as f64 * h - dx;
                    let edge = aperture.edge_rates_in(x0, x0 + h, y0, y0 + h)?;
                    let da = edge.iter().zip(&rate.edges).map(|(e, r)| e * r).sum::<f64>() / (h * h);
                    if da == 0.0 {
                        continue;
                    }
                    let (x, y) = (-1.0 + (i as f64 + 0.5) * h, -1.0 + (j as f64 + 0.5) * h);
                    let opd = compiled.opd_m(x, y) + tx * x + ty * y;
                    moved[j * n + i] += Complex64::from_polar(da * z.amplitude, k * opd);
                    d_area += da;
                }
            }
            d_weight += d_area * z.amplitude * z.amplitude;
        }
        Some((moved, d_weight))
    }

    /// The field of the last [`set_field`](Self::set_field), `N × N` row-major.
    pub fn field(&self) -> &[Complex64] {
        &self.field
    }

    /// `Σ_k Σ_j A_jk a_j²` of the last [`set_field`](Self::set_field) (pixel units): the OTF's
    /// normalization ([`OtfPlan::otf_of_field`](super::OtfPlan::otf_of_field)).
    pub fn weight(&self) -> f64 {
        self.weight
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The derivative of the composite field against central differences of `set_field` itself
    /// (the slow, obviously correct reference): two rings and a sector, each zone's amplitude,
    /// defocus and tilt moving at its own rate with one key `p`.
    #[test]
    fn field_derivative_matches_differences_of_the_field() {
        let apertures = vec![
            Arc::new(Aperture::ring(0.0, 0.5, None).unwrap()),
            Arc::new(Aperture::ring(0.5, 0.8, None).unwrap()),
            Arc::new(Aperture::sector(0.0, 2.0).unwrap()),
        ];
        let mut sampled = SampledZones::new(32, &apertures).unwrap();
        let lambda = 800e-9;
        // (amplitude, W020, tilt) and their rates per unit p
        let base = [(0.9, 0.3e-6, [0.1e-6, 0.0]), (0.7, -0.5e-6, [0.0, 0.2e-6]), (0.5, 1.1e-6, [-0.1e-6, 0.1e-6])];
        let rate = [(0.3, 0.2e-6, [0.0, 0.1e-6]), (-0.2, 0.4e-6, [0.3e-6, 0.0]), (0.1, -0.3e-6, [0.1e-6, 0.2e-6])];
        let at = |p: f64| -> Vec<ZoneField> {
            base.iter()
                .zip(&rate)
                .map(|(&(a, w, t), &(da, dw, dt))| ZoneField {
                    amplitude: a + p * da,
                    aberrations: Aberrations::defocus(w + p * dw),
                    tilt_m: [t[0] + p * dt[0], t[1] + p * dt[1]],
                })
                .collect()
        };
        let h = 1e-4;
        sampled.set_field(&at(h), lambda).unwrap();
        let (up, w_up) = (sampled.field().to_vec(), sampled.weight());
        sampled.set_field(&at(-h), lambda).unwrap();
        let (down, w_down) = (sampled.field().to_vec(), sampled.weight());
        let fields = at(0.0);
        let d_amplitude: Vec<f64> = rate.iter().map(|r| r.0).collect();
        let (moved, d_weight) = sampled
            .field_derivative(&fields, lambda, &d_amplitude, &|j, x, y| {
                rate[j].1 * (x * x + y * y) + rate[j].2[0] * x + rate[j].2[1] * y
            })
            .unwrap();
        let largest = moved.iter().map(|m| m.norm()).fold(0.0, f64::max);
        assert!(largest > 1.0, "{largest}");
        for (k, m) in moved.iter().enumerate() {
            let reference = (up[k] - down[k]) / (2.0 * h);
            assert!((m - reference).norm() < 1e-6 * largest, "pixel {k}: {m} vs {reference}");
        }
        let reference = (w_up - w_down) / (2.0 * h);
        assert!((d_weight - reference).abs() < 1e-9 * reference.abs(), "{d_weight} vs {reference}");
        // one per zone, or none
        assert!(sampled.field_derivative(&fields[..2], lambda, &d_amplitude[..2], &|_, _, _| 0.0).is_none());
    }

    /// The edges' part of [`SampledZones::rates_derivative`] against central differences of
    /// `set_field` on the zones re-sampled with their edges moved (the slow, obviously correct
    /// reference): two rings whose shared circle and outer rim move (the concentric layout's
    /// area fraction) and two wedges whose shared edge and last edge turn (the sectors'), with
    /// each zone's defocus and amplitude moving beside them.
    #[test]
    fn edge_rates_match_differences_of_the_resampled_field() {
        let lambda = 800e-9;
        let na = 0.2;
        let fields = vec![
            ZoneField { amplitude: 0.9, aberrations: Aberrations::defocus(0.4e-6), tilt_m: [0.1e-6, 0.0] },
            ZoneField { amplitude: 0.6, aberrations: Aberrations::defocus(-0.3e-6), tilt_m: [0.0, -0.2e-6] },
        ];
        // (the zones at a step p along the rates, the rates)
        type Zones = Box<dyn Fn(f64) -> Vec<Arc<Aperture>>>;
        let cases: Vec<(Zones, [[f64; 4]; 2])> = vec![
            (
                Box::new(|p| {
                    vec![
                        Arc::new(Aperture::ring(0.0, 0.55 + p, None).unwrap()),
                        Arc::new(Aperture::ring(0.55 + p, 0.85 + 0.5 * p, None).unwrap()),
                    ]
                }),
                [[0.0, 1.0, 0.0, 0.0], [1.0, 0.5, 0.0, 0.0]],
            ),
            (
                Box::new(|p| {
                    vec![
                        Arc::new(Aperture::sector(0.0, 2.0 + p).unwrap()),
                        Arc::new(Aperture::sector(2.0 + p, 4.5 + 2.0 * p).unwrap()),
                    ]
                }),
                [[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 1.0, 2.0]],
            ),
        ];
        for (zones, edges) in &cases {
            let rates = [
                crate::ZoneRate { amplitude: 0.2, defocus_m: 0.1e-6, edges: edges[0], ..Default::default() },
                crate::ZoneRate { image_shift_m: [0.0, 0.3e-6], edges: edges[1], ..Default::default() },
            ];
            let at = |p: f64| {
                let mut sampled = SampledZones::new(32, &zones(p)).unwrap();
                let moved: Vec<ZoneField> = fields
                    .iter()
                    .zip(&rates)
                    .map(|(f, r)| ZoneField {
                        amplitude: f.amplitude + p * r.amplitude,
                        aberrations: Aberrations::defocus(f.aberrations.w020_m + p * r.defocus_m),
                        tilt_m: [f.tilt_m[0] + p * na * r.image_shift_m[0], f.tilt_m[1] + p * na * r.image_shift_m[1]],
                    })
                    .collect();
                sampled.set_field(&moved, lambda).unwrap();
                (sampled.field().to_vec(), sampled.weight())
            };
            let h = 1e-6;
            let ((up, w_up), (down, w_down)) = (at(h), at(-h));
            let mut sampled = SampledZones::new(32, &zones(0.0)).unwrap();
            sampled.set_field(&fields, lambda).unwrap();
            let (moved, d_weight) = sampled.rates_derivative(&fields, lambda, &rates, na).unwrap();
            let largest = moved.iter().map(|m| m.norm()).fold(0.0, f64::max);
            assert!(largest > 1.0, "{largest}");
            for (k, m) in moved.iter().enumerate() {
                let reference = (up[k] - down[k]) / (2.0 * h);
                assert!((m - reference).norm() < 1e-5 * largest, "pixel {k}: {m} vs {reference}");
            }
            let reference = (w_up - w_down) / (2.0 * h);
            assert!((d_weight - reference).abs() < 1e-6 * reference.abs(), "{d_weight} vs {reference}");
        }
        // a mask's edges are not parameters
        let mask = SampledZones::new(16, &[Arc::new(Aperture::mask(|x, _| x > 0.0))]).unwrap();
        let one = [ZoneField { amplitude: 1.0, ..Default::default() }];
        let rate = [crate::ZoneRate { edges: [0.0, 1.0, 0.0, 0.0], ..Default::default() }];
        assert!(mask.rates_derivative(&one, lambda, &rate, na).is_none());
    }
}
