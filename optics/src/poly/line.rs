//! The line-spectrum engine ([`Engine::Monochromatic`]): one wavelength, one node per imaging
//! order, no spectral quadrature; each order by the exact 1-D OTF or, where its pupil or
//! wavefront needs it, by FFT.

use num_complex::Complex64;

use super::exact::{contributions, exact_along};
use super::grid::FftPath;
use super::spectral::{Nodes, Scene};
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
