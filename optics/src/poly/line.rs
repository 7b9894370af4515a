//! The line-spectrum engine ([`Engine::Monochromatic`]): one wavelength, one node per imaging
//! order, no spectral quadrature; each order by the exact 1-D OTF or, where its pupil or
//! wavefront needs it, by FFT.

use num_complex::Complex64;

use super::exact::{contributions, exact_along};
use super::grid::FftPath;
use super::spectral::{Nodes, RADIAL_ACCURACY, Scene};
use super::{Engine, FrequencyRule, OtfEngine};

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
    /// alone (the exact 1-D OTF): `Σ τ_o w_o ∂H/∂w_o / Σ τ_o` ([`crate::defocus_otf_log_derivative`])
    /// beside `Σ τ_o H / Σ τ_o`; `None` for any other order.
    fn otf_and_defocus_derivative(&self, frequency: f64) -> Option<(f64, f64)> {
        if self.fft.is_some() || self.nodes.direction_dependent() {
            return None;
        }
        let nuf = frequency.abs() * self.scene.f_number;
        let (mut value, mut derivative) = (0.0, 0.0);
        for node in &self.nodes.nodes {
            if node.table.is_some() || node.radial.is_some() || node.scale != 1.0 || node.shift != [0.0, 0.0] {
                return None;
            }
            let (s, w) = (nuf * node.lambda, node.w020 / node.lambda);
            value += node.weight * crate::defocus_otf(s, w);
            derivative += node.weight * crate::defocus_otf_log_derivative(s, w);
        }
        let total = self.nodes.total_weight;
        Some((value / total, derivative / total))
    }

    fn otf_along(&self, frequency: f64, azimuth: f64) -> Complex64 {
        match &self.fft {
            Some(fft) => fft.sum_along(&self.scene, frequency, azimuth) / self.nodes.total_weight,
            None => exact_along(&self.scene, &self.nodes, frequency, azimuth),
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
}
