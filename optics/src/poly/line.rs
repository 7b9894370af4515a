//! The line-spectrum engine ([`Engine::Monochromatic`]): one wavelength, one node per imaging
//! order, no spectral quadrature; each order by the exact 1-D OTF or, where its pupil or
//! wavefront needs it, by FFT.

use num_complex::Complex64;

use super::exact::{contributions, exact_along, exact_along_and_field_gradient};
use super::grid::{FftPath, Grids};
use super::spectral::{Nodes, RADIAL_ACCURACY, Scene};
use super::{AzimuthalMean, Engine, FrequencyRule, NoiseShape, OtfEngine, Polychromatic, WavefrontDirection};
use crate::Error;

/// A line spectrum's nodes, with the FFT grids of its orders where some order needs them.
#[derive(Debug)]
pub(super) struct Line<'a> {
    pub scene: Scene<'a>,
    pub nodes: Nodes,
    pub fft: Option<FftPath>,
}

impl OtfEngine for Line<'_> {
    fn engine(&self) -> Engine {
        Engine::Monochromatic { fft: self.fft.as_ref().map(|f| (f.pupil_samples, f.padded)) }
    }

    fn nodes(&self) -> &Nodes {
        &self.nodes
    }

    fn f_number(&self) -> f64 {
        self.scene.f_number
    }

    /// On the exact 1-D orders, as the exact engine's over a band: the largest `2π ν |∂Δ_o/∂θ|`
    /// over the line's orders (far orders included whatever their weight) and the frequencies
    /// read; `None` on the FFT path.
    fn field_lane_bound(&self) -> Option<f64> {
        if self.fft.is_some() {
            return None;
        }
        let top = self.scene.max_frequency.min(self.max_cutoff());
        let mut largest = 0.0_f64;
        for node in &self.nodes.nodes {
            let [rx, ry] = node.shift_rate?;
            largest = largest.max(rx.abs()).max(ry.abs());
        }
        Some(2.0 * std::f64::consts::PI * top * largest)
    }

    fn otf(&self, frequency: f64) -> f64 {
        if self.fft.is_some() {
            return self.otf_along(frequency, 0.0).re;
        }
        let mut sum = 0.0;
        contributions(&self.scene, &self.nodes, frequency, -self.scene.field_direction(), |v, _| sum += v);
        sum / self.nodes.total_weight
    }

    /// The line's OTF and its derivatives along the lens's wavefront directions
    /// (`LensModel::binary2_directions` at the line's wavelength, one list per order): each
    /// order's radial OTF and derivatives on the value's own rule
    /// (`RadialOrder::otf_and_derivatives` at the accuracy [`Node::otf`](super::spectral::Node::otf)
    /// reads the value at), summed with the orders' weights as the value is. `None` where some
    /// order is not a radial pupil on the radial engine, the OTF depends on direction, or the
    /// lens gives no directions.
    fn otf_and_gradient(&self, frequency: f64, gradient: &mut [f64]) -> Option<f64> {
        if self.fft.is_some() || self.nodes.direction_dependent() {
            return None;
        }
        let lambda = self.nodes.line?;
        let directions = self.scene.lens.binary2_directions(lambda)?;
        if directions.len() != self.nodes.nodes.len() {
            return None;
        }
        gradient.iter_mut().for_each(|g| *g = 0.0);
        let nuf = frequency.abs() * self.scene.f_number;
        let mut one = vec![0.0; gradient.len()];
        let mut value = 0.0;
        for (node, direction) in self.nodes.nodes.iter().zip(&directions) {
            let radial = match (&node.table, &node.radial) {
                (None, Some(r)) if direction.len() == gradient.len() => r,
                _ => return None,
            };
            value += node.weight * radial.otf_and_derivatives(nuf * node.lambda, RADIAL_ACCURACY, direction, &mut one);
            for (g, d) in gradient.iter_mut().zip(&one) {
                *g += node.weight * d;
            }
        }
        let total = self.nodes.total_weight;
        gradient.iter_mut().for_each(|g| *g /= total);
        Some(value / total)
    }

    /// The line's OTF and `∂O/∂ln K` where every order is a full, centred circle with defocus
    /// alone (the exact 1-D OTF): `Σ τ_o w_o ∂H/∂w_o / Σ τ_o` beside `Σ τ_o H / Σ τ_o`, the value
    /// [`otf`](OtfEngine::otf)'s bit for bit ([`order_lane`](Line::order_lane) with every
    /// `α_o = 1`, `γ_o = 0`); `None` for any other order.
    fn otf_and_defocus_derivative(&self, frequency: f64) -> Option<(f64, f64)> {
        self.order_lane(frequency, None)
    }

    fn otf_and_order_lane(&self, frequency: f64, rates: &[[f64; 2]]) -> Option<(f64, f64)> {
        self.order_lane(frequency, Some(rates))
    }

    /// The order lane ([`order_lane`](Line::order_lane)) with each order's rates along the
    /// design wavelength (`LensModel::design_wavelength_rates` at the line: `α_o = δW020_o/W020_o`,
    /// 0 where `W020_o = 0`, `w ∂H/∂w` being 0 there; `γ_o = δτ_o`); `None` where the lens gives
    /// no rates for its orders here.
    fn otf_and_design_lane(&self, frequency: f64) -> Option<(f64, f64)> {
        let lambda = self.nodes.line?;
        let rates = self.scene.lens.design_wavelength_rates(lambda, self.scene.field)?;
        if rates.len() != self.nodes.nodes.len() {
            return None;
        }
        let rates: Vec<[f64; 2]> = rates
            .iter()
            .zip(&self.nodes.nodes)
            .map(|(&[d_w020, d_tau], n)| [if n.w020 == 0.0 { 0.0 } else { d_w020 / n.w020 }, d_tau])
            .collect();
        self.order_lane(frequency, Some(&rates))
    }

    /// Off axis, where every order is an exact 1-D circle: the design wavelength's, the image
    /// shifts' scale and the defocus lanes of the exact engine on the line's own nodes
    /// ([`exact_along_and_field_gradient`]: each order turned by its own lateral colour), the
    /// value [`otf_along`](OtfEngine::otf_along)'s; `None` for other directions and on the FFT
    /// path (docs/physics.md, "Gradients: several orders under a line off axis").
    fn otf_along_and_gradient(
        &self,
        frequency: f64,
        azimuth: f64,
        directions: &[WavefrontDirection],
        gradient: &mut [Complex64],
    ) -> Option<Complex64> {
        let carried = |d: &WavefrontDirection| {
            matches!(
                d,
                WavefrontDirection::DesignWavelength
                    | WavefrontDirection::ImageShift
                    | WavefrontDirection::Defocus
                    | WavefrontDirection::FieldAngle(_)
            )
        };
        if self.fft.is_some() || !directions.iter().all(carried) {
            return None;
        }
        exact_along_and_field_gradient(&self.scene, &self.nodes, None, frequency, azimuth, directions, gradient)
    }

    fn otf_along(&self, frequency: f64, azimuth: f64) -> Complex64 {
        match &self.fft {
            Some(fft) => fft.sum_along(&self.scene, frequency, azimuth) / self.nodes.total_weight,
            None => exact_along(&self.scene, &self.nodes, None, frequency, azimuth),
        }
    }

    fn direction_dependent(&self) -> bool {
        self.fft.is_some() || self.nodes.direction_dependent()
    }

    fn frequency_rule(&self) -> FrequencyRule {
        match &self.fft {
            Some(fft) => FrequencyRule::Fixed { cell: fft.finest_cell(self.scene.f_number) },
            None => FrequencyRule::Adaptive { min_panels: 4.0 },
        }
    }

    /// On the line's FFT grids: the derivative of the mean over the `count` azimuths from
    /// `first` with respect to `ln F#` at fixed pupils (each grid read at `s = νcF#` moving with
    /// F#, the value's fixed rule in ν, azimuths, weights and pixel MTF: the discrete rule's
    /// frequency-scale term, `FftPath::scale_over_azimuth` on the line's one level; no
    /// Richardson level). `None` on the exact 1-D engine.
    fn scale_over_azimuth(&self, first: f64, count: usize) -> Option<f64> {
        let fft = self.fft.as_ref()?;
        Some(fft.scale_over_azimuth(&self.scene, &self.nodes, first, count))
    }

    fn wavefront_gradient_over_azimuth(
        &self,
        first: f64,
        count: usize,
        directions: &[WavefrontDirection],
    ) -> Result<Option<Vec<f64>>, Error> {
        self.grid_gradient(first, count, directions, None)
    }

    fn wavefront_gradient_over_azimuth_over_noise(
        &self,
        first: f64,
        count: usize,
        directions: &[WavefrontDirection],
        noise: &NoiseShape,
    ) -> Result<Option<Vec<f64>>, Error> {
        self.grid_gradient(first, count, directions, Some(noise))
    }
}

impl Line<'_> {
    /// On the line's FFT grids: the derivative of the mean MTF averaged over the `count`
    /// azimuths from `first` along each of `directions` (docs/physics.md, "Gradients: 2-D pupils
    /// under a line"), by the FFT path's forward mode on the line's own grids
    /// ([`Grids::gradient_over_azimuth`] at the line's sampling, one node per order, no
    /// Richardson level: the value's fixed rule in ν, its azimuths, interpolation, weights and
    /// pixel MTF; with `noise`, each frequency's weight divided by `n(ν)` as the value's is).
    /// `Ok(None)` where no order is on the grids (the exact 1-D engine's lanes are the line's).
    fn grid_gradient(
        &self,
        first: f64,
        count: usize,
        directions: &[WavefrontDirection],
        noise: Option<&NoiseShape>,
    ) -> Result<Option<Vec<f64>>, Error> {
        let Some(fft) = &self.fft else { return Ok(None) };
        // the line's grids at its own sampling (`FftPath::build`, as `choose` builds them)
        let grids = Grids::new(self.scene, self.nodes.clone(), Some(fft.pupil_samples), f64::INFINITY)?;
        grids.gradient_over_azimuth(first, count, directions, noise)
    }

    /// The OTF at `frequency` as [`otf`](OtfEngine::otf) computes it, bit for bit (the same
    /// nodes below the cutoff, the same points through [`crate::otf::defocus_otf_many_and_log_derivative_within`],
    /// whose values are [`crate::otf::defocus_otf_many`]'s, summed in the same order), and beside
    /// it the lane of [`OtfEngine::otf_and_order_lane`]: per node `w_o α_o (w ∂H/∂w)_o + q γ_o H_o`
    /// (`α_o = 1`, `γ_o = 0` without `rates`), minus `O Σ_o q γ_o`, over the total weight. `None`
    /// where some order is not a full centred circle with a defocus alone (a table, a radial
    /// pupil, a scaled pupil, an image shift) or `rates` does not give one entry per node.
    fn order_lane(&self, frequency: f64, rates: Option<&[[f64; 2]]>) -> Option<(f64, f64)> {
        if self.fft.is_some() || self.nodes.direction_dependent() {
            return None;
        }
        let nodes = &self.nodes.nodes;
        if rates.is_some_and(|r| r.len() != nodes.len())
            || nodes.iter().any(|n| !n.is_defocused_circle() || n.scale != 1.0 || n.shift != [0.0, 0.0])
        {
            return None;
        }
        let rate = |o: usize| rates.map_or([1.0, 0.0], |r| r[o]);
        // the line's rule weight q (each node's weight is q τ_o)
        let q = self.nodes.samples.first().map_or(0.0, |s| s.1);
        let nu = frequency.abs();
        let nuf = nu * self.scene.f_number;
        let cut = if nu > 0.0 { 1.0 / nuf } else { f64::INFINITY };
        let passing: Vec<usize> = (0..nodes.len()).filter(|&o| nodes[o].lambda < cut).collect();
        let points: Vec<(f64, f64)> = passing
            .iter()
            .map(|&o| (nuf * nodes[o].lambda / nodes[o].scale, nodes[o].w020 / nodes[o].lambda))
            .collect();
        let (mut values, mut lanes) = (vec![0.0; points.len()], vec![0.0; points.len()]);
        crate::otf::defocus_otf_many_and_log_derivative_within(&points, &mut values, &mut lanes, 0.0);
        let (mut sum, mut lane) = (0.0, 0.0);
        for ((&o, value), d) in passing.iter().zip(&values).zip(&lanes) {
            let node = &nodes[o];
            sum += node.weight * value;
            let [alpha, gamma] = rate(o);
            lane += node.weight * alpha * d + q * gamma * value;
        }
        let total = self.nodes.total_weight;
        let value = sum / total;
        let moved: f64 = (0..nodes.len()).map(|o| q * rate(o)[1]).sum();
        Some((value, (lane - value * moved) / total))
    }
}

impl Polychromatic<'_> {
    /// Under a line whose orders are on FFT grids ([`Engine::Monochromatic`] with grids): the
    /// mean MTF averaged over azimuth ([`mean_mtf_over_azimuth`](Self::mean_mtf_over_azimuth),
    /// with `noise` the mean of `P |O| / n`) and its derivative along each of `directions` on
    /// the same rules (docs/physics.md, "Gradients: 2-D pupils under a line"). `Ok(None)` on
    /// another engine, or where an order is not a radial pupil on the grids.
    ///
    /// # Errors
    /// Building the grids again ([`Error`] of the FFT layer).
    pub fn line_mean_mtf_over_azimuth_and_gradient(
        &self,
        first: f64,
        directions: &[WavefrontDirection],
        noise: Option<&NoiseShape>,
    ) -> Result<Option<(AzimuthalMean, Vec<f64>)>, Error> {
        if !matches!(self.engine(), Engine::Monochromatic { fft: Some(_) }) {
            return Ok(None);
        }
        let mean = self.mean_mtf_over_azimuth(first, noise);
        let gradient = match noise {
            None => self.engine.wavefront_gradient_over_azimuth(first, mean.azimuths, directions)?,
            Some(n) => self.engine.wavefront_gradient_over_azimuth_over_noise(first, mean.azimuths, directions, n)?,
        };
        Ok(gradient.map(|g| (mean, g)))
    }

    /// Under a line whose orders are on FFT grids: the derivative of
    /// [`mean_mtf_over_azimuth`](Self::mean_mtf_over_azimuth) (white noise) with respect to
    /// `ln F#` at fixed pupils, each grid read at `s = νcF#` moving with F# on the value's own
    /// fixed rule, azimuths and pixel MTF (docs/physics.md, "Gradients: the F-number, the focal
    /// length and the wavelengths under a line on the grids"). `None` on another engine.
    pub fn line_mean_mtf_over_azimuth_scale_lane(&self, first: f64) -> Option<f64> {
        if !matches!(self.engine(), Engine::Monochromatic { fft: Some(_) }) {
            return None;
        }
        let mean = self.mean_mtf_over_azimuth(first, None);
        self.engine.scale_over_azimuth(first, mean.azimuths)
    }
}
