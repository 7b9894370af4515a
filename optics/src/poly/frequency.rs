//! The frequency integration, written once over any engine: the mean of `P(ν) |OTF(ν)|` over
//! `[0, ν_max]` (paper eq. 1), by adaptive Gauss–Kronrod split at the OTF's sign changes, or by
//! a fixed composite rule on the FFT engine's interpolated grids.

use std::f64::consts::PI;

use num_complex::Complex64;

use super::{
    Engine, FrequencyRule, MAX_DEPTH, MAX_PANELS, NoiseShape, Polychromatic, WavefrontDirection, Work, level_error,
    nested_error,
};

/// Where the oscillations of the OTF in ν have averaged out over the spectrum, in units of the
/// averaging frequency `ν_s` ([`OtfEngine::averaged_defocus`](super::OtfEngine::averaged_defocus)):
/// their damping `exp(−(ν/ν_s)²/2)` is `e^{−32}` = 1e-14 there. Beyond, the OTF is the smooth
/// average over the defocus spread, decaying about as `C/ν`: one panel in `ln ν`, where
/// `ν |OTF|` is about constant, takes the rest of the range.
pub(super) const AVERAGED_DECAY: f64 = 8.0;

/// Azimuths of the first level of the nested trapezoid rule over azimuth, on `[0, π)` (the
/// tangential and sagittal directions among them).
pub const FIRST_AZIMUTHS: usize = 8;

/// Azimuths of the first level where the tolerance is looser than [`LOOSE_TOLERANCE`] and the
/// overlap engine computes each azimuth's values (docs/physics.md, "Zernike terms on the overlap
/// engine", "Why its time falls from 1e-4 to 1e-3"): the rule is nested from 4, whose difference
/// from 8 bounds the error of the 4 as that from 16 bounds the 8's, and the finer is kept.
pub const LOOSE_FIRST_AZIMUTHS: usize = 4;

/// The tolerance (relative) above which the overlap engine's rule over azimuth starts from
/// [`LOOSE_FIRST_AZIMUTHS`]; at it and below, [`FIRST_AZIMUTHS`] (values unchanged there).
pub const LOOSE_TOLERANCE: f64 = 1e-4;

/// The most azimuths the nested trapezoid rule over azimuth takes on `[0, π)`.
pub const MAX_AZIMUTHS: usize = 256;

/// Share of the tolerance the rule over azimuth may spend (relative to the mean).
pub const AZIMUTH_SHARE: f64 = 0.25;

/// The mean MTF of a pupil without rotational symmetry averaged over azimuth
/// ([`Polychromatic::mean_mtf_over_azimuth`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AzimuthalMean {
    /// The mean over azimuth of the mean MTF along each direction.
    pub mean: f64,
    /// The mean along the first azimuth (the field direction: tangential).
    pub tangential: f64,
    /// The mean across it (sagittal).
    pub sagittal: f64,
    /// Azimuths on `[0, π)` the trapezoid rule took.
    pub azimuths: usize,
    /// The change of the average at the last doubling (absolute): the error estimate of the
    /// rule over azimuth, within [`AZIMUTH_SHARE`] of the tolerance times the mean unless
    /// [`MAX_AZIMUTHS`] was reached.
    pub change: f64,
    /// What the means along every azimuth took, summed.
    pub work: Work,
}

fn add(a: Work, b: Work) -> Work {
    Work {
        frequency_panels: a.frequency_panels + b.frequency_panels,
        otf_evaluations: a.otf_evaluations + b.otf_evaluations,
        sign_changes: a.sign_changes + b.sign_changes,
        closed_form_evaluations: a.closed_form_evaluations + b.closed_form_evaluations,
        spectral_evaluations: a.spectral_evaluations + b.spectral_evaluations,
        ..b
    }
}
use crate::quad;

/// What [`Polychromatic::mean_mtf_and_binary2_gradient`] gathers as the value's frequency rule
/// runs: the OTF's derivatives at each frequency read (`lanes` a frequency), and the nodes and
/// weights of the rule's accepted panels (each weight times `P(ν)` and the sign of the OTF
/// there: `∂|O| = sign(O) ∂O`).
#[derive(Debug, Default)]
pub(super) struct Recording {
    lanes: usize,
    /// the frequency's bits → its derivatives' place in `derivatives`
    at: std::collections::HashMap<u64, usize>,
    derivatives: Vec<f64>,
    accepted: Vec<(f64, f64)>,
    /// an OTF the engine gave no derivatives for
    failed: bool,
    /// the wavefront directions the engine differentiates along an azimuth
    /// ([`Polychromatic::mean_mtf_over_azimuth_and_overlap_gradient`]); empty for the radial
    /// engine's lanes
    directions: Vec<WavefrontDirection>,
    /// the parameters of the lens's order derivatives the engine differentiates along
    /// ([`Polychromatic::mean_mtf_and_field_gradient`]); empty for the other lanes
    fields: Vec<usize>,
    /// the Seidel lanes at zero ([`Polychromatic::mean_mtf_and_seidel_lanes`]) instead of the
    /// Binary 2 lanes
    seidel: bool,
    /// each node's `[α_o, γ_o]` of the order lane ([`Polychromatic::mean_mtf_and_order_lane`]);
    /// `None` for the defocus lane `∂O/∂ln K` and the other lanes
    rates: Option<Vec<[f64; 2]>>,
    /// the design wavelength's lane ([`Polychromatic::mean_mtf_and_design_lane`]) instead of
    /// the defocus lane
    design: bool,
}

/// What [`Polychromatic::mean_mtf_and_defocus_derivative`] returns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DefocusDerivative {
    /// The mean MTF, as [`Polychromatic::mean_mtf`] computes it.
    pub mean: f64,
    /// `D_K = (1/ν_max) ∫ P sign(O) ∂O/∂ln K dν`: the mean's derivative with respect to a common
    /// relative change of every order's defocus, `s = νλF#` fixed.
    pub defocus: f64,
    /// `(1/ν_max) ∫ ν P′(ν) |O(ν)| dν`, the pixel MTF's term of the integration by parts in ν
    /// (0 without the pixel MTF).
    pub pixel_slope: f64,
    /// What the mean took.
    pub work: Work,
}

/// What [`Polychromatic::mean_mtf_and_design_and_edge_lanes`] returns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DesignAndEdgeLanes {
    /// The mean MTF, as [`Polychromatic::mean_mtf`] computes it.
    pub mean: f64,
    /// `[∂M̄/∂ln λ0, ∂M̄/∂lo, ∂M̄/∂hi]`: the design wavelength's lane and the band's edges'.
    pub design_and_edges: [f64; 3],
    /// `D_K`, as [`DefocusDerivative::defocus`].
    pub defocus: f64,
    /// `P_ν`, as [`DefocusDerivative::pixel_slope`].
    pub pixel_slope: f64,
    /// What the mean took.
    pub work: Work,
}

impl Polychromatic<'_> {
    /// The mean MTF ([`mean_mtf`](Self::mean_mtf)) and, in the same pass, its derivative with
    /// respect to each Binary 2 coefficient of the lens (`LensModel::binary2_directions`; per
    /// radian) (docs/physics.md, "Gradients"):
    ///
    /// ```text
    /// ∂M̄/∂A_j = (1/ν_max) ∫ P(ν) sign(O(ν)) ∂O(ν)/∂A_j dν
    /// ```
    ///
    /// on the value's own rules: the engine returns each OTF with its derivatives on the spectral
    /// level it accepts for the value, and the frequency rule's accepted panels (split at the
    /// OTF's sign changes, where `|O|` has its kink) integrate them with the value's weights. No
    /// second search: the derivatives ride on the value's evaluations. `None` where no gradient
    /// is given this way: the lens has no Binary 2 coefficients, the field is off axis, the OTF
    /// depends on direction, or the engine is not the per-frequency exact one of radially
    /// symmetric orders.
    pub fn mean_mtf_and_binary2_gradient(&self) -> Option<(f64, Vec<f64>, Work)> {
        let lanes = self.binary2_lanes()?;
        self.recorded_mean_and_gradient(Recording { lanes, ..Recording::default() })
    }

    /// The mean MTF ([`mean_mtf`](Self::mean_mtf)), bit for bit, and in the same pass its
    /// derivative along each of `parameters` of the lens's order derivatives
    /// (`LensModel::order_derivatives`: a library lens's parameter bias; docs/physics.md,
    /// "Gradients: a library's parameter bias"):
    ///
    /// ```text
    /// ∂M̄/∂b = (1/ν_max) ∫ P(ν) sign(O(ν)) ∂O(ν)/∂b dν
    /// ```
    ///
    /// each `∂O` beside its OTF value on the spectral level the value accepts (the engine's
    /// values are the value's own, so the frequency rule makes the value's decisions), integrated
    /// with the frequency rule's accepted weights. `None` where no such gradient is given: off
    /// axis, an OTF that depends on direction, an engine other than the per-frequency exact one,
    /// or an order without derivatives.
    pub fn mean_mtf_and_field_gradient(&self, parameters: &[usize]) -> Option<(f64, Vec<f64>, Work)> {
        if parameters.is_empty()
            || !self.scene.field.is_on_axis()
            || self.direction_dependent()
            || !matches!(self.engine.frequency_rule(), FrequencyRule::Adaptive { .. })
        {
            return None;
        }
        let lanes = parameters.len();
        self.recorded_mean_and_gradient(Recording { lanes, fields: parameters.to_vec(), ..Recording::default() })
    }

    /// The mean MTF ([`mean_mtf`](Self::mean_mtf)) and, in the same pass, its derivatives per
    /// metre along a spherical aberration `W040 ρ⁴` and a constant defocus `W220 ρ²` at zero
    /// (docs/physics.md, "Gradients: Seidel terms at zero"):
    ///
    /// ```text
    /// ∂M̄/∂W = (1/ν_max) ∫ P(ν) sign(O(ν)) ∂O(ν)/∂W dν
    /// ```
    ///
    /// each `∂O` beside its OTF value from the engine's own rule (the closed form's, on its
    /// pieces in the pupil angle), integrated with the frequency rule's accepted weights (split
    /// at the OTF's sign changes, `P` included). `None` where the engine gives no such lanes
    /// (every engine but the closed form), off axis, or where the OTF depends on direction.
    pub fn mean_mtf_and_seidel_lanes(&self) -> Option<(f64, [f64; 2], Work)> {
        if !self.scene.field.is_on_axis()
            || self.direction_dependent()
            || !matches!(self.engine.frequency_rule(), FrequencyRule::Adaptive { .. })
            || self.engine.engine() != Engine::ClosedForm
        {
            return None;
        }
        let (mean, lanes, work) =
            self.recorded_mean_and_gradient(Recording { lanes: 2, seidel: true, ..Recording::default() })?;
        Some((mean, [lanes[0], lanes[1]], work))
    }

    /// The mean MTF ([`mean_mtf`](Self::mean_mtf)), bit for bit, and in the same pass its
    /// derivatives along the detected spectrum's own changes (docs/physics.md, "Gradients: a
    /// line's wavelength and a blackbody's temperature", "Gradients: a top-hat's edges"):
    /// with `rate`, along `∂ln ρ = r(λ)` (a blackbody's temperature: Planck's `∂ln B/∂T`), one
    /// lane; with `edges`, along the band's lower and upper ends ([`spectral_ends`](Self::spectral_ends)),
    /// two lanes:
    ///
    /// ```text
    /// ∂M̄ = (1/ν_max) ∫ P(ν) sign(O(ν)) ∂O(ν) dν
    /// ```
    ///
    /// each `∂O` beside its OTF value from the value's own sums on the spectral level each panel
    /// accepts (the per-frequency product rule), integrated with the frequency rule's accepted
    /// weights. `r` should be centred (`⟨r⟩ ≈ 0` over the detected weights): the lane is then
    /// no difference of nearly equal sums. `None` where the engine gives no such lanes (every
    /// engine but the per-frequency product rule), off axis, or where the OTF depends on
    /// direction.
    pub fn mean_mtf_and_spectral_lanes(
        &self,
        rate: Option<&dyn Fn(f64) -> f64>,
        edges: bool,
    ) -> Option<(f64, Vec<f64>, Work)> {
        let lanes = usize::from(rate.is_some()) + if edges { 2 } else { 0 };
        if lanes == 0
            || !self.scene.field.is_on_axis()
            || self.direction_dependent()
            || !matches!(self.engine.frequency_rule(), FrequencyRule::Adaptive { .. })
            || self.engine.spectral_ends().is_none()
        {
            return None;
        }
        let rate = rate.map(|r| (r, self.spectral_average(|l, _| r(l))));
        *self.gradient.borrow_mut() = Some(Recording { lanes, ..Recording::default() });
        let (mean, work) = self.mean_of(&|nu| {
            let mut derivatives = vec![0.0; lanes];
            let value = if nu == 0.0 {
                Some(1.0)
            } else {
                self.engine.otf_and_spectral_lanes(nu, rate, edges, &mut derivatives)
            };
            self.record(nu, value, &derivatives)
        });
        let recording = self.gradient.borrow_mut().take()?;
        self.integrate_recorded(mean, recording, work)
    }

    /// The mean MTF ([`mean_mtf`](Self::mean_mtf)), bit for bit, and in the same pass the
    /// design wavelength's lane ([`mean_mtf_and_design_lane`](Self::mean_mtf_and_design_lane)'s
    /// `∂M̄/∂ln λ0`), the band's two edge lanes
    /// ([`mean_mtf_and_spectral_lanes`](Self::mean_mtf_and_spectral_lanes)'s with `edges`) and
    /// the defocus lane with the pixel MTF's term of the integration by parts
    /// ([`mean_mtf_and_defocus_derivative`](Self::mean_mtf_and_defocus_derivative)'s `D_K` and
    /// `P_ν`): `([∂M̄/∂ln λ0, ∂M̄/∂lo, ∂M̄/∂hi], D_K, P_ν)`, each beside its OTF value on the
    /// spectral level each panel accepts (the defocus and design lanes from the same `w ∂H/∂w`),
    /// integrated with the frequency rule's accepted weights (docs/physics.md, "Gradients: the
    /// dispersion-engineered lens"). `None` where the engine gives no such lanes (every engine
    /// but the per-frequency product rule), off axis, or where the OTF depends on direction.
    pub fn mean_mtf_and_design_and_edge_lanes(&self) -> Option<DesignAndEdgeLanes> {
        if !self.scene.field.is_on_axis()
            || self.direction_dependent()
            || !matches!(self.engine.frequency_rule(), FrequencyRule::Adaptive { .. })
            || self.engine.spectral_ends().is_none()
        {
            return None;
        }
        *self.gradient.borrow_mut() = Some(Recording { lanes: 5, ..Recording::default() });
        let (mean, work) = self.mean_of(&|nu| {
            let mut lanes = [0.0; 4];
            let value = if nu == 0.0 { Some(1.0) } else { self.engine.otf_and_design_and_edge_lanes(nu, &mut lanes) };
            // the fifth: P_ν's integrand ν P′/P |O| (the accepted weights carry P sign(O))
            let [design, lo, hi, defocus] = lanes;
            self.record(nu, value, &[design, lo, hi, defocus, value.unwrap_or(0.0) * self.pixel_log_slope(nu)])
        });
        let recording = self.gradient.borrow_mut().take()?;
        let (mean, found, work) = self.integrate_recorded(mean, recording, work)?;
        Some(DesignAndEdgeLanes {
            mean,
            design_and_edges: [found[0], found[1], found[2]],
            defocus: found[3],
            pixel_slope: found[4],
            work,
        })
    }

    /// The mean MTF ([`mean_mtf`](Self::mean_mtf)), bit for bit, and in the same pass
    ///
    /// ```text
    /// (1/ν_max) ∫ P(ν) sign(O(ν)) L_k(ν) dν,   L = lanes(ν, O(ν))
    /// ```
    ///
    /// for lanes the caller forms at each frequency the rule reads from the OTF value there (a
    /// band edge's `O_x − O`, `O_x` the OTF at the edge's single wavelength: docs/physics.md,
    /// "Gradients: the dispersion-engineered lens"), integrated with the frequency rule's
    /// accepted weights (split at the OTF's sign changes and at every spectral panel end's
    /// cutoff, `P` included): a lane whose kinks fall at those cuts rides on the value's own
    /// error control. `None` off axis where the field moves the OTF, where the OTF depends on
    /// direction, or on the FFT path's fixed rule.
    pub fn mean_mtf_and_lanes<const K: usize>(
        &self,
        lanes: &dyn Fn(f64, f64) -> [f64; K],
    ) -> Option<(f64, [f64; K], Work)> {
        if !(self.scene.field.is_on_axis() || self.field_independent())
            || self.direction_dependent()
            || !matches!(self.engine.frequency_rule(), FrequencyRule::Adaptive { .. })
        {
            return None;
        }
        *self.gradient.borrow_mut() = Some(Recording { lanes: K, ..Recording::default() });
        let (mean, work) = self.mean_of(&|nu| {
            let v = self.otf(nu);
            self.record(nu, Some(v), &lanes(nu, v))
        });
        let recording = self.gradient.borrow_mut().take()?;
        let (mean, found, work) = self.integrate_recorded(mean, recording, work)?;
        Some((mean, std::array::from_fn(|k| found[k]), work))
    }

    /// The band `[lo, hi]` (m) whose ends the edge lanes of
    /// [`mean_mtf_and_spectral_lanes`](Self::mean_mtf_and_spectral_lanes) move, where the engine
    /// gives them (the per-frequency product rule: the spectrum's support, or a Gaussian's
    /// ±7σ where narrower).
    pub fn spectral_ends(&self) -> Option<(f64, f64)> {
        self.engine.spectral_ends()
    }

    /// Keeps `value` (the OTF at `nu`) and its lanes `derivatives` in the recording; where the
    /// engine gave none, marks the recording failed and reads the OTF alone.
    fn record(&self, nu: f64, value: Option<f64>, derivatives: &[f64]) -> f64 {
        let mut recording = self.gradient.borrow_mut();
        let Some(r) = recording.as_mut() else { return value.unwrap_or(f64::NAN) };
        match value {
            Some(v) => {
                let place = r.derivatives.len();
                r.derivatives.extend_from_slice(derivatives);
                r.at.insert(nu.to_bits(), place);
                v
            }
            None => {
                r.failed = true;
                drop(recording);
                self.otf(nu)
            }
        }
    }

    /// The recorded lanes integrated with the frequency rule's accepted weights over `ν_max`.
    fn integrate_recorded(&self, mean: f64, recording: Recording, work: Work) -> Option<(f64, Vec<f64>, Work)> {
        if recording.failed {
            return None;
        }
        let lanes = recording.lanes;
        let mut gradient = vec![0.0; lanes];
        for &(nu, w) in &recording.accepted {
            let i = *recording.at.get(&nu.to_bits())?;
            for (g, d) in gradient.iter_mut().zip(&recording.derivatives[i..i + lanes]) {
                *g += w * d;
            }
        }
        gradient.iter_mut().for_each(|g| *g /= self.scene.max_frequency);
        Some((mean, gradient, work))
    }

    /// The number of Binary 2 lanes (the lens's wavefront directions) where the radial
    /// engine's lanes apply: on axis, a rotationally symmetric OTF, the adaptive frequency rule,
    /// and at least one direction; `None` elsewhere. The guard of
    /// [`mean_mtf_and_binary2_gradient`](Self::mean_mtf_and_binary2_gradient) and its
    /// noise-weighted twin.
    fn binary2_lanes(&self) -> Option<usize> {
        if !self.scene.field.is_on_axis()
            || self.direction_dependent()
            || !matches!(self.engine.frequency_rule(), FrequencyRule::Adaptive { .. })
        {
            return None;
        }
        let lambda = self.engine.nodes().nodes.first()?.lambda;
        let lanes = self.scene.lens.binary2_directions(lambda)?.first()?.len();
        (lanes > 0).then_some(lanes)
    }

    /// The mean over `[0, ν_max]` of `P |O| / n` for a non-white noise spectrum `n`
    /// ([`mean_mtf_over_noise`](Self::mean_mtf_over_noise), bit for bit) and, in the same pass,
    /// its derivative with respect to each Binary 2 coefficient of the lens (the lanes of
    /// [`mean_mtf_and_binary2_gradient`](Self::mean_mtf_and_binary2_gradient); docs/physics.md,
    /// "Gradients under a noise spectrum"):
    ///
    /// ```text
    /// ∂/∂A_j (1/ν_max) ∫ P |O| / n dν = (1/ν_max) ∫ P(ν) sign(O(ν)) ∂O(ν)/∂A_j / n(ν) dν
    /// ```
    ///
    /// `n` does not depend on the lens: each recorded lane is divided by `n(ν)` as the value is,
    /// and the frequency rule's accepted weights of the noise-weighted mean integrate them. `None`
    /// where [`mean_mtf_and_binary2_gradient`](Self::mean_mtf_and_binary2_gradient) is.
    pub fn mean_mtf_over_noise_and_binary2_gradient(&self, noise: &NoiseShape) -> Option<(f64, Vec<f64>, Work)> {
        let lanes = self.binary2_lanes()?;
        *self.gradient.borrow_mut() = Some(Recording { lanes, ..Recording::default() });
        let (mean, work) = self.mean_of_cut(&|nu| self.over_noise(nu, self.recorded_otf(nu), noise), noise.rows());
        let recording = self.gradient.borrow_mut().take()?;
        self.integrate_recorded(mean, recording, work)
    }

    /// `value / n(ν)` (`value` the integrand just read at `nu`), and every number the recording
    /// kept at `nu` by that reading divided by `n(ν)` as well: the lanes of the noise-weighted
    /// mean `(1/ν_max) ∫ P |O| / n dν`, whose weight `1/n` does not move with the lens.
    fn over_noise(&self, nu: f64, value: f64, noise: &NoiseShape) -> f64 {
        let n = noise.value(nu);
        if let Some(r) = self.gradient.borrow_mut().as_mut()
            && let Some(&place) = r.at.get(&nu.to_bits())
        {
            r.derivatives[place..].iter_mut().for_each(|d| *d /= n);
        }
        value / n
    }

    /// The mean MTF with `recording` set, and the recorded lanes integrated with the frequency
    /// rule's accepted weights over `ν_max`: the one pass both gradients above take. `None`
    /// where the recording failed or an accepted frequency has no lanes.
    fn recorded_mean_and_gradient(&self, recording: Recording) -> Option<(f64, Vec<f64>, Work)> {
        *self.gradient.borrow_mut() = Some(recording);
        let (mean, work) = self.mean_of(&|nu| self.recorded_otf(nu));
        let recording = self.gradient.borrow_mut().take()?;
        self.integrate_recorded(mean, recording, work)
    }

    /// The mean MTF ([`mean_mtf`](Self::mean_mtf)) and, in the same pass, what its derivatives
    /// with respect to the F-number and the focal length need (docs/physics.md, "Gradients: the
    /// F-number and the focal length on the value's rule"):
    ///
    /// ```text
    /// D_K   = (1/ν_max) ∫ P(ν) sign(O(ν)) ∂O(ν)/∂ln K dν
    /// P_ν   = (1/ν_max) ∫ ν P′(ν) |O(ν)| dν
    /// ```
    ///
    /// `D_K` the derivative with respect to a common relative change of every order's defocus at
    /// fixed `s = νλF#` (the engine's `∂O/∂ln K` beside each OTF value: the closed form's lane on
    /// its own rule in `t`, a line's orders, the per-frequency product rule's `w ∂H/∂w` on the
    /// spectral level each panel accepts), `P_ν` the pixel MTF's part of the integration by
    /// parts in `ν` (0 without it; `νP′/P = x cot x − 1`, `x = πpν`); both with the frequency
    /// rule's accepted weights (split at the OTF's sign changes, `P` included). `None` where the
    /// engine gives no such lane, the field is off axis where it moves the OTF
    /// ([`field_independent`](Self::field_independent)), or the OTF depends on direction.
    pub fn mean_mtf_and_defocus_derivative(&self) -> Option<DefocusDerivative> {
        self.mean_with_defocus_lane(None, false)
    }

    /// [`mean_mtf_and_defocus_derivative`](Self::mean_mtf_and_defocus_derivative) with the lane
    /// of a line whose orders move each by its own rates (`rates[o] = [α_o, γ_o]`, one per order
    /// of the lens at the line): `defocus` is then `(1/ν_max) ∫ P sign(O) L dν` with
    /// `L = (Σ_o [τ_o α_o w ∂H_o/∂w + γ_o H_o] − O Σ_o γ_o) / Σ_o τ_o` (a change of each
    /// order's `ln W020` by `α_o` and of its efficiency by `γ_o`, `s = νλF#` fixed; docs/physics.md,
    /// "Gradients: a line's wavelength and a blackbody's temperature"). The mean is
    /// [`mean_mtf`](Self::mean_mtf)'s bit for bit where the engine reads its values from the
    /// value's own forms (the line engine). `None` where the engine gives no such lane (not a
    /// line, an order other than a full centred circle with a defocus alone).
    pub fn mean_mtf_and_order_lane(&self, rates: &[[f64; 2]]) -> Option<DefocusDerivative> {
        self.mean_with_defocus_lane(Some(rates.to_vec()), false)
    }

    /// [`mean_mtf_and_defocus_derivative`](Self::mean_mtf_and_defocus_derivative) with the lane
    /// of the lens's design wavelength λ0: `defocus` is then `(1/ν_max) ∫ P sign(O) ∂O/∂ln λ0 dν`,
    /// `∂O/∂ln λ0 = (∫ρ Σ_o [τ_o ∂H/∂w δw_o + δτ_o H_o] − O ∫ρ Σ_o δτ_o)/∫ρ Σ_o τ_o` at fixed
    /// `s = νλF#` (each order's `δW020_o`, `δτ_o` from `LensModel::design_wavelength_rates`;
    /// docs/physics.md, "Gradients: the design wavelength"), each `∂O` beside its OTF value on
    /// the value's own rule (the closed form's lane along `δW020 = d0 + d1 λ` on its rule in `t`,
    /// a line's order lane, the per-frequency product rule's `w ∂H/∂w` on the level each panel
    /// accepts) and integrated with the frequency rule's accepted weights (`P` included).
    /// `None` where the engine gives no such lane (the lens gives no rates, the FFT path, the
    /// reference panels rule), off axis where the field moves the OTF, or where the OTF depends
    /// on direction.
    pub fn mean_mtf_and_design_lane(&self) -> Option<DefocusDerivative> {
        self.mean_with_defocus_lane(None, true)
    }

    /// The mean MTF ([`mean_mtf`](Self::mean_mtf)), bit for bit, and in the same pass, for a
    /// lens of `orders` orders at every wavelength, each order's own design wavelength lane and
    /// then each order's efficiency lane (`2 × orders` numbers: `(1/ν_max) ∫ P sign(O) ∂O dν`,
    /// `∂O` the engine's lanes of order `o` alone, its normalization's
    /// rate subtracted): the lanes of every channel of an interleaved multiplexed lens at once
    /// (docs/physics.md, "Gradients: the multiplexed lens"), each `∂O` beside its OTF value on
    /// the spectral level the value accepts and integrated with the frequency rule's accepted
    /// weights (`P` included); then, from the same OTFs, the F-number's and focal length's two
    /// numbers `D_K` and `P_ν` ([`DefocusDerivative::defocus`] and
    /// [`DefocusDerivative::pixel_slope`]: `2 × orders + 2` numbers in all). `None` where the engine gives no such lanes (every engine but the
    /// per-frequency product rule), off axis where the field moves the OTF, or where the OTF
    /// depends on direction.
    pub fn mean_mtf_and_order_lanes(&self, orders: usize) -> Option<(f64, Vec<f64>, Work)> {
        if orders == 0
            || !(self.scene.field.is_on_axis() || self.field_independent())
            || self.direction_dependent()
            || !matches!(self.engine.frequency_rule(), FrequencyRule::Adaptive { .. })
        {
            return None;
        }
        // the engine's 2n + 1, then P_ν's integrand ν P′/P |O| (the accepted weights carry P sign(O))
        let lanes = 2 * orders + 2;
        *self.gradient.borrow_mut() = Some(Recording { lanes, ..Recording::default() });
        let (mean, work) = self.mean_of(&|nu| {
            let mut derivatives = vec![0.0; lanes];
            let value = match nu {
                0.0 => Some(1.0),
                _ => self.engine.otf_and_order_lanes(nu, &mut derivatives[..lanes - 1]),
            };
            derivatives[lanes - 1] = value.unwrap_or(0.0) * self.pixel_log_slope(nu);
            self.record(nu, value, &derivatives)
        });
        let recording = self.gradient.borrow_mut().take()?;
        self.integrate_recorded(mean, recording, work)
    }

    /// `∂ln(∫ρ Σ_o τ_o dλ)/∂ln λ0` on the nodes that make the engine's normalization (each
    /// sample's weight times `Σ_o ∂τ_o/∂ln λ0`, `LensModel::design_wavelength_rates`): the design
    /// wavelength's rate of the detected signal N. `None` where the lens gives no rates.
    pub fn design_signal_rate(&self) -> Option<f64> {
        self.signal_rate(|lens, lambda, field| {
            Some(lens.design_wavelength_rates(lambda, field)?.iter().map(|r| r[1]).sum::<f64>())
        })
    }

    /// `Σ w ∂τ/Σ w τ` over the nodes that make the engine's normalization, `∂τ` each sample's
    /// `rate` (the move of its orders' summed efficiency, `None` where the lens gives none).
    fn signal_rate(&self, rate: impl Fn(&dyn crate::LensModel, f64, crate::Field) -> Option<f64>) -> Option<f64> {
        let nodes = self.engine.nodes();
        let mut moved = 0.0;
        for &(lambda, w, part) in &nodes.samples {
            if w == 0.0 {
                continue;
            }
            moved += w * rate(self.scene.part(part).lens, lambda, self.scene.field)?;
        }
        Some(moved / nodes.total_weight)
    }

    /// `∂ln(∫ρ Σ_o τ_o dλ)` along `key` on the nodes that make the engine's normalization (each
    /// sample's weight times `Σ_o ∂τ_o`, `LensModel::zone_rates`): the key's rate of the
    /// detected signal N, per unit of the key. `None` where the lens gives no rates.
    pub fn zone_signal_rate(&self, key: crate::ZoneKey) -> Option<f64> {
        self.signal_rate(|lens, lambda, field| {
            Some(lens.zone_rates(lambda, field, key)?.iter().map(|r| r.efficiency).sum::<f64>())
        })
    }

    /// `∫ρ τ_o dλ / ∫ρ Σ_o τ_o dλ` for each of the lens's `orders` orders on the nodes that make
    /// the engine's normalization: each order's share of the detected signal N, its efficiency's
    /// rate `∂ln N/∂ln τ_o` ([`mean_mtf_and_order_lanes`](Self::mean_mtf_and_order_lanes)'s
    /// efficiency lanes). `None` where some wavelength has another count of orders.
    pub fn order_signal_shares(&self, orders: usize) -> Option<Vec<f64>> {
        let nodes = self.engine.nodes();
        let mut shares = vec![0.0; orders];
        for &(lambda, w, part) in &nodes.samples {
            if w == 0.0 {
                continue;
            }
            let found = self.scene.part(part).lens.orders(lambda, self.scene.field);
            if found.len() != orders {
                return None;
            }
            for (share, order) in shares.iter_mut().zip(&found) {
                *share += w * order.efficiency;
            }
        }
        Some(shares.into_iter().map(|s| s / nodes.total_weight).collect())
    }

    /// The mean with the defocus lane (`rates` `None`), the order lane or the design
    /// wavelength's lane (`design`) recorded beside it.
    fn mean_with_defocus_lane(&self, rates: Option<Vec<[f64; 2]>>, design: bool) -> Option<DefocusDerivative> {
        // off axis where the field does not move the OTF (no image displaced, every rate 0: the
        // refractive lens, its stop at the lens), the OTF is the one on axis
        if !(self.scene.field.is_on_axis() || self.field_independent())
            || self.direction_dependent()
            || !matches!(self.engine.frequency_rule(), FrequencyRule::Adaptive { .. })
        {
            return None;
        }
        *self.gradient.borrow_mut() = Some(Recording { lanes: 2, rates, design, ..Recording::default() });
        let (mean, work) = self.mean_of(&|nu| self.recorded_defocus_otf(nu));
        let recording = self.gradient.borrow_mut().take()?;
        if recording.failed {
            return None;
        }
        // ν P′(ν)/P(ν) for P = |sin x / x|, x = π p ν (x ≤ π/2 up to Nyquist)
        let slope = |nu: f64| self.pixel_log_slope(nu);
        let (mut d_k, mut pixel) = (0.0, 0.0);
        for &(nu, w) in &recording.accepted {
            let i = *recording.at.get(&nu.to_bits())?;
            let (d, v) = (recording.derivatives[i], recording.derivatives[i + 1]);
            d_k += w * d;
            pixel += w * v * slope(nu);
        }
        let top = self.scene.max_frequency;
        Some(DefocusDerivative { mean, defocus: d_k / top, pixel_slope: pixel / top, work })
    }

    /// The OTF at `nu` with its defocus derivative and itself kept in the recording.
    fn recorded_defocus_otf(&self, nu: f64) -> f64 {
        let value = {
            let recording = self.gradient.borrow();
            match recording.as_ref().and_then(|r| r.rates.as_deref()) {
                _ if nu == 0.0 => Some((1.0, 0.0)),
                _ if recording.as_ref().is_some_and(|r| r.design) => self.engine.otf_and_design_lane(nu),
                None => self.engine.otf_and_defocus_derivative(nu),
                Some(rates) => self.engine.otf_and_order_lane(nu, rates),
            }
        };
        let mut recording = self.gradient.borrow_mut();
        let Some(r) = recording.as_mut() else { return value.map_or(f64::NAN, |(v, _)| v) };
        match value {
            Some((v, d)) => {
                r.at.insert(nu.to_bits(), r.derivatives.len());
                r.derivatives.extend([d, v]);
                v
            }
            None => {
                r.failed = true;
                drop(recording);
                self.otf(nu)
            }
        }
    }

    /// The OTF at `nu` with its derivatives kept in the recording.
    fn recorded_otf(&self, nu: f64) -> f64 {
        let (lanes, fields, seidel) =
            self.gradient.borrow().as_ref().map_or((0, Vec::new(), false), |r| (r.lanes, r.fields.clone(), r.seidel));
        let mut derivatives = vec![0.0; lanes];
        let value = if nu == 0.0 {
            Some(1.0)
        } else if seidel {
            let mut two = [0.0; 2];
            let value = self.engine.otf_and_seidel_lanes(nu, &mut two);
            derivatives.copy_from_slice(&two);
            value
        } else if fields.is_empty() {
            self.engine.otf_and_gradient(nu, &mut derivatives)
        } else {
            self.engine.otf_and_field_gradient(nu, &fields, &mut derivatives)
        };
        let mut recording = self.gradient.borrow_mut();
        let Some(r) = recording.as_mut() else { return value.unwrap_or(f64::NAN) };
        match value {
            Some(v) => {
                let place = r.derivatives.len();
                r.derivatives.extend_from_slice(&derivatives);
                r.at.insert(nu.to_bits(), place);
                v
            }
            None => {
                r.failed = true;
                drop(recording);
                self.otf(nu)
            }
        }
    }

    /// Keeps an accepted node of the frequency rule (ν, its weight in `∫ P |O| dν` times the
    /// sign of the OTF there) while a gradient is recorded.
    fn accept(&self, nu: f64, weight: f64) {
        if let Some(r) = self.gradient.borrow_mut().as_mut() {
            r.accepted.push((nu, weight));
        }
    }

    /// Whether a gradient is being recorded.
    fn recording(&self) -> bool {
        self.gradient.borrow().is_some()
    }

    /// The frequency rule's share of the tolerance: all of it where the spectral integral is
    /// exact to rounding (closed form, panels rule, a line), the rest after
    /// [`SPECTRAL_SHARE`](super::spectral::SPECTRAL_SHARE) where product integration spent that.
    fn frequency_tolerance(&self) -> f64 {
        if self.engine.nodes().interpolated {
            (1.0 - super::spectral::SPECTRAL_SHARE) * self.asked_tolerance
        } else {
            self.asked_tolerance
        }
    }

    /// The mean of the MTF over `[0, max_frequency]` and what it took.
    ///
    /// Adaptive Gauss–Kronrod (7/15) on frequency panels: a panel is accepted when the Kronrod
    /// and Gauss sums of `P |OTF_poly|` differ by less than the tolerance of the
    /// frequency range times its share of the range, and bisected otherwise. A panel whose
    /// samples change sign is split at the located zeros first, so `|OTF_poly|` is only ever
    /// integrated where it is smooth. The initial panels are sized by the weighted-RMS defocus.
    pub fn mean_mtf(&self) -> (f64, Work) {
        if self.direction_dependent() {
            return self.mean_mtf_along(0.0);
        }
        self.mean_of(&|nu| self.otf(nu))
    }

    /// The mean of the MTF along `azimuth` (radians from the x axis) over `[0, max_frequency]`:
    /// [`mean_mtf`](Self::mean_mtf) for the complex OTF of a system with lateral colour. Without
    /// image displacements it equals [`mean_mtf`](Self::mean_mtf).
    pub fn mean_mtf_along(&self, azimuth: f64) -> (f64, Work) {
        if !self.direction_dependent() {
            return self.mean_mtf();
        }
        // the FFT engine's sampling choice read this azimuth at both levels with the same fixed
        // rule: its two means, extrapolated as `mean_of` would
        if let (Some(plan), Some((coarse, fine)), FrequencyRule::Fixed { cell }) =
            (self.engine.richardson(), self.engine.means_along(azimuth), self.engine.frequency_rule())
        {
            let nodes = self.engine.nodes();
            let (panels, evaluations) = super::grid::fixed_rule(self.active_top(), cell);
            let work = Work {
                spectral_panels: nodes.panels.len(),
                spectral_nodes: nodes.nodes.len(),
                spectral_interpolated: nodes.interpolated,
                frequency_panels: panels,
                otf_evaluations: 2 * evaluations,
                ..Work::default()
            };
            return (plan.extrapolate(coarse, fine).value, work);
        }
        // |OTF| ≥ 0: no sign changes to split at, only isolated zeros the adaptive rule resolves
        self.mean_of(&|nu| self.otf_along(nu, azimuth).norm())
    }

    /// The mean over `[0, max_frequency]` of `P(ν) |OTF(ν)| / n(ν)` for a non-white noise
    /// spectrum `n` (paper eq. 1 text: "if this is not the case, the SNR can be placed inside the
    /// integral"): times SNR0 it is the ASNR with the noise amplitude `n(ν) σ` at each frequency.
    /// Along `azimuth` when the OTF depends on direction.
    pub fn mean_mtf_over_noise(&self, noise: &NoiseShape, azimuth: f64) -> (f64, Work) {
        if self.direction_dependent() {
            self.mean_of_cut(&|nu| self.otf_along(nu, azimuth).norm() / noise.value(nu), noise.rows())
        } else {
            self.mean_of_cut(&|nu| self.otf(nu) / noise.value(nu), noise.rows())
        }
    }

    /// Whether the OTF is 2-D: a grid of a sampled pupil (the FFT engine, or a line spectrum's
    /// FFT grids), or a table holding each wavelength's whole PSF (a PSF stack without
    /// rotational symmetry, [`OtfTable::with_planes`](crate::OtfTable::with_planes)): an OTF
    /// with no rotational symmetry, whose ASNR takes the mean MTF averaged over azimuth
    /// ([`mean_mtf_over_azimuth`](Self::mean_mtf_over_azimuth)).
    pub fn has_pupil_grid(&self) -> bool {
        matches!(self.engine(), Engine::Fft { .. } | Engine::Overlap { .. } | Engine::Monochromatic { fft: Some(_) })
            || self.has_psf_planes()
    }

    /// Whether the 2-D OTF comes from a table of each wavelength's whole PSF (a PSF stack read
    /// in 2-D, [`OtfTable::with_planes`](crate::OtfTable::with_planes)), not a sampled pupil.
    pub fn has_psf_planes(&self) -> bool {
        self.engine.nodes().nodes.iter().any(|n| n.table.as_ref().is_some_and(|t| t.is_two_dimensional()))
    }

    /// The mean MTF averaged over azimuth (docs/physics.md, "Pupils without rotational
    /// symmetry"): `(1/ν_max) ∫_0^{ν_max} (1/π) ∫_0^π P(ν) |OTF(ν, φ)| dφ dν`, the mean of
    /// `P |OTF|` over the disc of radius `ν_max` in polar measure `dν dφ` (the radial integral of
    /// the 1-D mean, averaged over directions; `|OTF|` is π-periodic in φ since
    /// `OTF(−ν) = OTF(ν)*`). With a non-white `noise` spectrum, of `P |OTF| / n` instead.
    ///
    /// The φ integral is the trapezoid rule on `M` azimuths `φ_k = first + kπ/M` (spectrally
    /// accurate for a smooth periodic function), nested: `M` = 8, 16, … until two successive
    /// averages differ by at most [`AZIMUTH_SHARE`] of the tolerance relative to the mean (their
    /// difference bounds the error of the coarser one), or [`MAX_AZIMUTHS`]. Each azimuth's mean
    /// is [`mean_mtf_along`](Self::mean_mtf_along)'s. The tangential (along `first`) and sagittal
    /// (across) means are two of the azimuths.
    pub fn mean_mtf_over_azimuth(&self, first: f64, noise: Option<&NoiseShape>) -> AzimuthalMean {
        self.azimuthal_mean(first, &mut |azimuth: f64| match noise {
            None => self.mean_mtf_along(azimuth),
            Some(shape) => self.mean_mtf_over_noise(shape, azimuth),
        })
    }

    /// The nested trapezoid rule over azimuth of [`mean_mtf_over_azimuth`](Self::mean_mtf_over_azimuth)
    /// with each azimuth's mean from `along`. The average is the plain mean over every azimuth
    /// read (each doubling halves the old average and adds the new azimuths' share).
    fn azimuthal_mean(&self, first: f64, along: &mut dyn FnMut(f64) -> (f64, Work)) -> AzimuthalMean {
        let mut work = Work::default();
        let mut means: Vec<f64> = Vec::with_capacity(MAX_AZIMUTHS);
        let mut count = self.first_azimuths();
        for k in 0..count {
            let (m, w) = along(first + PI * k as f64 / count as f64);
            means.push(m);
            work = add(work, w);
        }
        let tangential = means[0];
        let sagittal = means[count / 2];
        let mut average = means.iter().sum::<f64>() / count as f64;
        let mut change = f64::INFINITY;
        while count < MAX_AZIMUTHS {
            // the new azimuths sit halfway between the old ones
            let mut added = 0.0;
            for k in 0..count {
                let (m, w) = along(first + PI * (2 * k + 1) as f64 / (2 * count) as f64);
                added += m;
                work = add(work, w);
            }
            count *= 2;
            let refined = 0.5 * average + added / count as f64;
            change = (refined - average).abs();
            average = refined;
            if change <= AZIMUTH_SHARE * self.tolerance() * average.abs() {
                break;
            }
        }
        AzimuthalMean { mean: average, tangential, sagittal, azimuths: count, change, work }
    }

    /// The first level of the rule over azimuth: [`LOOSE_FIRST_AZIMUTHS`] on the overlap engine
    /// at a tolerance looser than [`LOOSE_TOLERANCE`] (each azimuth costs it a full set of OTF
    /// values; a grid's readings cost little), else [`FIRST_AZIMUTHS`].
    fn first_azimuths(&self) -> usize {
        if matches!(self.engine.engine(), Engine::Overlap { .. }) && self.tolerance() > LOOSE_TOLERANCE {
            LOOSE_FIRST_AZIMUTHS
        } else {
            FIRST_AZIMUTHS
        }
    }

    /// The mean MTF averaged over azimuth ([`mean_mtf_over_azimuth`](Self::mean_mtf_over_azimuth),
    /// white noise) on the overlap engine, and its derivative with respect to each of
    /// `directions` on the same rules (docs/physics.md, "Gradients: Seidel terms on the overlap
    /// engine"): at each azimuth the value's adaptive frequency rule runs on
    /// `|O|` with each OTF's derivatives from the engine
    /// (`OtfEngine::otf_along_and_gradient`: forward mode on the overlap quadrature's own
    /// nodes), `∂|O| = Re(O* ∂O)/|O|` (0 where `O = 0`, the kink of `|O|`) kept per frequency
    /// read, and the accepted panels' nodes and weights (pixel MTF included) integrate them;
    /// the azimuths' derivatives are averaged as their means are. `None` where the engine gives
    /// no derivative for some direction.
    pub fn mean_mtf_over_azimuth_and_overlap_gradient(
        &self,
        first: f64,
        directions: &[WavefrontDirection],
    ) -> Option<(AzimuthalMean, Vec<f64>)> {
        if !matches!(self.engine.frequency_rule(), FrequencyRule::Adaptive { .. }) {
            return None;
        }
        let lanes = directions.len();
        let mut sum = vec![0.0; lanes];
        let mean = self.azimuthal_mean_with_lanes(first, directions, None, &mut |_, w, recorded| {
            for (g, d) in sum.iter_mut().zip(&recorded[..lanes]) {
                *g += w * d;
            }
        })?;
        // each azimuth's mean is (1/ν_max) ∫ P |O| dν; the average is over every azimuth read
        let scale = 1.0 / (self.scene.max_frequency * mean.azimuths as f64);
        Some((mean, sum.into_iter().map(|g| g * scale).collect()))
    }

    /// [`mean_mtf_over_azimuth_and_overlap_gradient`](Self::mean_mtf_over_azimuth_and_overlap_gradient)
    /// under a non-white noise spectrum `n`: the mean over azimuth of `(1/ν_max) ∫ P |O| / n dν`
    /// ([`mean_mtf_over_azimuth`](Self::mean_mtf_over_azimuth) with `noise`, bit for bit) and its
    /// derivative along each of `directions`, each lane `Re(O* ∂O)/|O|` divided by `n(ν)` as the
    /// value is (docs/physics.md, "Gradients under a noise spectrum"): on the overlap engine and
    /// on the exact 1-D engine where its OTF depends on direction (a circular iris's decentre,
    /// the field angles' lateral colour, the defocus lane through the iris). `None` where the
    /// white one is, or where the OTF does not depend on direction.
    pub fn mean_mtf_over_azimuth_over_noise_and_overlap_gradient(
        &self,
        first: f64,
        directions: &[WavefrontDirection],
        noise: &NoiseShape,
    ) -> Option<(AzimuthalMean, Vec<f64>)> {
        if !matches!(self.engine.engine(), Engine::Overlap { .. } | Engine::Exact1d)
            || !matches!(self.engine.frequency_rule(), FrequencyRule::Adaptive { .. })
            || !self.direction_dependent()
        {
            return None;
        }
        let lanes = directions.len();
        let mut sum = vec![0.0; lanes];
        let mean = self.azimuthal_mean_with_lanes(first, directions, Some(noise), &mut |_, w, recorded| {
            for (g, d) in sum.iter_mut().zip(&recorded[..lanes]) {
                *g += w * d;
            }
        })?;
        let scale = 1.0 / (self.scene.max_frequency * mean.azimuths as f64);
        Some((mean, sum.into_iter().map(|g| g * scale).collect()))
    }

    /// The nested rule over azimuth of [`mean_mtf_over_azimuth`](Self::mean_mtf_over_azimuth)
    /// (white noise, or the noise spectrum `noise`) with the OTF's lanes along `directions` recorded at each azimuth (forward
    /// mode on the engine's nodes, `∂|O| = Re(O* ∂O)/|O|`, then `|O|` itself: `lanes + 1` numbers
    /// per frequency read), and `take(ν, w, recorded)` called for each node the frequency rule
    /// accepted at each azimuth, with its weight `w` (the pixel MTF included) and the numbers
    /// recorded at `ν`, azimuth after azimuth in the order they are read. The one recording loop
    /// of [`mean_mtf_over_azimuth_and_overlap_gradient`](Self::mean_mtf_over_azimuth_and_overlap_gradient)
    /// and [`mean_mtf_over_azimuth_and_defocus_lane`](Self::mean_mtf_over_azimuth_and_defocus_lane).
    /// `None` where some OTF had no lanes from the engine or an accepted node was not recorded.
    fn azimuthal_mean_with_lanes(
        &self,
        first: f64,
        directions: &[WavefrontDirection],
        noise: Option<&NoiseShape>,
        take: &mut dyn FnMut(f64, f64, &[f64]),
    ) -> Option<AzimuthalMean> {
        let lanes = directions.len();
        let mut read = 0usize;
        let mut failed = false;
        let mean = self.azimuthal_mean(first, &mut |azimuth: f64| {
            *self.gradient.borrow_mut() =
                Some(Recording { lanes, directions: directions.to_vec(), ..Recording::default() });
            let (mean, work) = match noise {
                None => self.mean_of(&|nu| self.recorded_modulus_along(nu, azimuth)),
                Some(shape) => self.mean_of_cut(
                    &|nu| self.over_noise(nu, self.recorded_modulus_along(nu, azimuth), shape),
                    shape.rows(),
                ),
            };
            match self.gradient.borrow_mut().take() {
                Some(r) if !r.failed => {
                    for &(nu, w) in &r.accepted {
                        match r.at.get(&nu.to_bits()) {
                            Some(&i) => take(nu, w, &r.derivatives[i..=i + lanes]),
                            None => failed = true,
                        }
                    }
                }
                _ => failed = true,
            }
            read += 1;
            (mean, work)
        });
        (!failed && read == mean.azimuths).then_some(mean)
    }

    /// The mean MTF averaged over azimuth on the overlap engine with the defocus lane
    /// `D_K = ∂M̄/∂ln K` beside it ([`WavefrontDirection::Defocus`]: every order's own `W020`
    /// scaled by `1 + ε`, `s = νλF#` fixed; forward mode on the overlap quadrature's nodes, as
    /// [`mean_mtf_over_azimuth_and_overlap_gradient`](Self::mean_mtf_over_azimuth_and_overlap_gradient)),
    /// and the pixel MTF's term of the integration by parts in ν, `P_ν = (1/ν_max) ∫ ν P′ |O| dν`
    /// averaged over the same azimuths (0 without it; `νP′/P = x cot x − 1`, `x = πpν`), both
    /// with the accepted panels' weights at each azimuth (docs/physics.md, "Gradients: the
    /// F-number and the focal length with Seidel terms"). `None` where the engine is not the
    /// overlap engine or gives no lane.
    pub fn mean_mtf_over_azimuth_and_defocus_lane(&self, first: f64) -> Option<DefocusDerivative> {
        if !matches!(self.engine.engine(), Engine::Overlap { .. } | Engine::Exact1d)
            || !matches!(self.engine.frequency_rule(), FrequencyRule::Adaptive { .. })
        {
            return None;
        }
        let slope = |nu: f64| {
            self.scene.pixel_pitch.map_or(0.0, |p| {
                let x = PI * p * nu;
                if x.abs() < 1e-4 { -x * x / 3.0 - x.powi(4) / 45.0 } else { x / x.tan() - 1.0 }
            })
        };
        let (mut d_k, mut pixel) = (0.0, 0.0);
        // the lane, then |O|, at each accepted frequency
        let mean =
            self.azimuthal_mean_with_lanes(first, &[WavefrontDirection::Defocus], None, &mut |nu, w, recorded| {
                d_k += w * recorded[0];
                pixel += w * recorded[1] * slope(nu);
            })?;
        let scale = 1.0 / (self.scene.max_frequency * mean.azimuths as f64);
        Some(DefocusDerivative { mean: mean.mean, defocus: d_k * scale, pixel_slope: pixel * scale, work: mean.work })
    }

    /// [`mean_mtf_over_azimuth_and_defocus_lane`](Self::mean_mtf_over_azimuth_and_defocus_lane)
    /// off axis: beside the defocus lane `D_K`, the image shifts' lane
    /// `D_Δ = ∂M̄/∂ln Δ` ([`WavefrontDirection::ImageShift`]: every node's lateral colour scaled
    /// by `1 + ε`), on the same nodes and accepted weights, returned after the
    /// [`DefocusDerivative`] (docs/physics.md, "Gradients: the F-number and the focal length off
    /// axis"). The rule over azimuth is the value's nested trapezoid rule from `first`, doubled
    /// until the mean and the lanes each move by at most [`AZIMUTH_SHARE`] of the tolerance
    /// relative to the larger of the mean and the lanes' size: the lanes carry `2πν u·Δ` beside
    /// each value, so they turn faster with the azimuth than `|O|` does (a harmonic lens's far
    /// orders: 1.8e-5 of the gradient off where the value's own count of azimuths was kept).
    /// `None` where the engine is not the overlap engine or the exact 1-D engine, or gives no
    /// lane.
    pub fn mean_mtf_over_azimuth_and_aperture_lanes(&self, first: f64) -> Option<(DefocusDerivative, f64)> {
        if !matches!(
            self.engine.engine(),
            Engine::Overlap { .. } | Engine::Exact1d | Engine::Monochromatic { fft: None }
        ) || !matches!(self.engine.frequency_rule(), FrequencyRule::Adaptive { .. })
        {
            return None;
        }
        let directions = [WavefrontDirection::Defocus, WavefrontDirection::ImageShift];
        let (average, work) = self.azimuth_refined_lanes(first, &directions, None)?;
        let [mean, defocus, shift, pixel_slope] = average[..] else { return None };
        Some((DefocusDerivative { mean, defocus, pixel_slope, work }, shift))
    }

    /// [`mean_mtf_over_azimuth_and_aperture_lanes`](Self::mean_mtf_over_azimuth_and_aperture_lanes)
    /// under a non-white noise spectrum `n`: `(G, D̃_K, D̃_Δ)`, the mean over azimuth of
    /// `(1/ν_max) ∫ P |O| / n dν` and the defocus and image shifts' lanes with each `∂|O|` divided
    /// by `n(ν)`, on the value's frequency rule cut at the table's rows (`mean_of_cut`) and the
    /// same rule over azimuth (docs/physics.md, "Gradients under a noise spectrum"). `None` where
    /// the white one is.
    pub fn mean_mtf_over_azimuth_over_noise_and_aperture_lanes(
        &self,
        first: f64,
        noise: &NoiseShape,
    ) -> Option<(f64, f64, f64)> {
        if !matches!(self.engine.engine(), Engine::Overlap { .. } | Engine::Exact1d)
            || !matches!(self.engine.frequency_rule(), FrequencyRule::Adaptive { .. })
        {
            return None;
        }
        let directions = [WavefrontDirection::Defocus, WavefrontDirection::ImageShift];
        let (average, _) = self.azimuth_refined_lanes(first, &directions, Some(noise))?;
        let [mean, defocus, shift, _] = average[..] else { return None };
        Some((mean, defocus, shift))
    }

    /// The design wavelength's lanes off axis on the exact 1-D engine, beside the mean over
    /// azimuth (white, or over the noise spectrum `noise`): `(M̄, D_λ0, D_Δ)`, `D_λ0` the
    /// lane of each order's defocus and efficiency moving with `ln λ0`
    /// ([`WavefrontDirection::DesignWavelength`], the normalization's rate not subtracted) and
    /// `D_Δ` the image shifts' scale ([`WavefrontDirection::ImageShift`]), on the value's nodes
    /// and accepted weights, each `∂|O|` divided by `n(ν)` under a noise spectrum, on the rule
    /// over azimuth of [`mean_mtf_over_azimuth_and_aperture_lanes`](Self::mean_mtf_over_azimuth_and_aperture_lanes)
    /// (docs/physics.md, "Gradients: the design wavelength off axis"). On the overlap engine (the
    /// full circle with Seidel and Zernike terms, on and off axis) the same lanes on its
    /// quadrature's nodes ("Gradients: the design wavelength with Seidel and Zernike terms").
    /// `None` where the engine is not the exact 1-D engine (direction-dependent) or the overlap
    /// engine on its adaptive rule, or gives no lane.
    pub fn mean_mtf_over_azimuth_and_design_lanes(
        &self,
        first: f64,
        noise: Option<&NoiseShape>,
    ) -> Option<(f64, f64, f64, Work)> {
        let taken = match self.engine.engine() {
            Engine::Exact1d => self.direction_dependent(),
            Engine::Overlap { .. } => true,
            _ => false,
        };
        if !taken || !matches!(self.engine.frequency_rule(), FrequencyRule::Adaptive { .. }) {
            return None;
        }
        let directions = [WavefrontDirection::DesignWavelength, WavefrontDirection::ImageShift];
        let (average, work) = self.azimuth_refined_lanes(first, &directions, noise)?;
        let [mean, design, shift, _] = average[..] else { return None };
        Some((mean, design, shift, work))
    }

    /// [`mean_mtf_over_azimuth_and_design_lanes`](Self::mean_mtf_over_azimuth_and_design_lanes)
    /// with the field angles' lanes in place of the image shifts' scale: `(M̄, D_λ0, D_Δ)`, `D_Δ`
    /// the sum of the lanes [`WavefrontDirection::FieldAngle`] `0` and `1`, each node's shift
    /// moving by its order's rates (`LensModel::image_shift_field_rates`) along x and y together,
    /// `∂O` gaining `−2πi ν u·δΔ_o` times each node's turned value. For a lens seen through a view
    /// whose shift rates are one order's own (a multiplexed lens's channel wavelength off axis,
    /// docs/physics.md "Gradients: the multiplexed lens"), where the design wavelength's
    /// scale of every order's shift is not the motion; the field direction does not move, so no
    /// turn of the rule's azimuths is added. `None` where that one is.
    pub fn mean_mtf_over_azimuth_and_design_shift_lanes(
        &self,
        first: f64,
        noise: Option<&NoiseShape>,
    ) -> Option<(f64, f64, f64)> {
        if self.engine.engine() != Engine::Exact1d
            || !matches!(self.engine.frequency_rule(), FrequencyRule::Adaptive { .. })
            || !self.direction_dependent()
        {
            return None;
        }
        let directions = [
            WavefrontDirection::DesignWavelength,
            WavefrontDirection::FieldAngle(0),
            WavefrontDirection::FieldAngle(1),
        ];
        let (average, _) = self.azimuth_refined_lanes(first, &directions, noise)?;
        let [mean, design, x, y, _] = average[..] else { return None };
        Some((mean, design, x + y))
    }

    /// A line's lanes off axis where its several orders are exact 1-D circles each turned by its
    /// own lateral colour (the harmonic lens): `[M̄, D_λ0, D_Δ, D_K, P_ν]` over azimuth from
    /// `first` (white, or over the noise spectrum `noise`), `D_λ0` the design wavelength's lane
    /// ([`WavefrontDirection::DesignWavelength`], the normalization's rate not subtracted), `D_Δ`
    /// the image shifts' scale ([`WavefrontDirection::ImageShift`]), `D_K` every order's defocus
    /// scaled ([`WavefrontDirection::Defocus`]) and `P_ν` the pixel MTF's term, on the line
    /// engine's own nodes and the value's accepted weights, on the rule over azimuth of
    /// [`mean_mtf_over_azimuth_and_aperture_lanes`](Self::mean_mtf_over_azimuth_and_aperture_lanes)
    /// (docs/physics.md, "Gradients: several orders under a line off axis"). `None` where the
    /// engine is not the line's exact one (the FFT path) or the OTF does not depend on direction.
    pub fn mean_mtf_over_azimuth_and_line_lanes(
        &self,
        first: f64,
        noise: Option<&NoiseShape>,
    ) -> Option<([f64; 5], Work)> {
        if self.engine.engine() != (Engine::Monochromatic { fft: None })
            || !matches!(self.engine.frequency_rule(), FrequencyRule::Adaptive { .. })
            || !self.direction_dependent()
        {
            return None;
        }
        let directions =
            [WavefrontDirection::DesignWavelength, WavefrontDirection::ImageShift, WavefrontDirection::Defocus];
        let (average, work) = self.azimuth_refined_lanes(first, &directions, noise)?;
        let [mean, design, shift, defocus, pixel] = average[..] else { return None };
        Some(([mean, design, shift, defocus, pixel], work))
    }

    /// A line's defocus lane over azimuth on the line's exact 1-D engine: `[M̄, D_K, P_ν]` from
    /// `first` (white, or over the noise spectrum `noise`), `D_K` every order's defocus scaled by
    /// `1 + ε` with a decentred iris's tilt `W020 (2d/NA)`, which scales with it
    /// ([`WavefrontDirection::Defocus`]), and `P_ν` the pixel MTF's term, on the line engine's own
    /// nodes and the value's accepted weights, on the rule over azimuth of
    /// [`mean_mtf_over_azimuth_and_aperture_lanes`](Self::mean_mtf_over_azimuth_and_aperture_lanes)
    /// (docs/physics.md, "Gradients: a line's wavelength through an iris"). `None` where the
    /// engine is not the line's exact one (the FFT path) or some order is not a defocused circle.
    pub fn line_mean_mtf_over_azimuth_and_defocus_lane(
        &self,
        first: f64,
        noise: Option<&NoiseShape>,
    ) -> Option<[f64; 3]> {
        if self.engine.engine() != (Engine::Monochromatic { fft: None })
            || !matches!(self.engine.frequency_rule(), FrequencyRule::Adaptive { .. })
        {
            return None;
        }
        let (average, _) = self.azimuth_refined_lanes(first, &[WavefrontDirection::Defocus], noise)?;
        let [mean, defocus, pixel] = average[..] else { return None };
        Some([mean, defocus, pixel])
    }

    /// A line's field angles off axis where its several orders are exact 1-D circles each turned
    /// by its own lateral colour (the harmonic lens's orders, the interleaved lens's channels):
    /// the derivative of the mean over azimuth (white, or of `P |O| / n` under `noise`) along
    /// each of `directions` ([`WavefrontDirection::FieldAngle`]: each order's value times
    /// `−2πi ν u·∂Δ_o/∂θ`) on the line engine's own nodes and the value's frequency rule, its
    /// accepted weights (docs/physics.md, "Gradients: the field point under a line"). The rule
    /// over azimuth is the value's nested trapezoid rule from `first`, doubled until the lanes
    /// move by at most [`AZIMUTH_SHARE`] of the frequency rule's tolerance relative to their own
    /// size, not the mean's: the orders' shifts differ, so `|O|` has structure in azimuth on the
    /// scale of `1/(2πν |Δ_o − Δ_o′|)`, and a gradient small against the mean (a line near the
    /// harmonic lens's design wavelength, its other orders' weights small) would be left to the
    /// mean's error. `None` where the engine is not the line's exact one, the OTF does not depend
    /// on direction, or some direction is not a field angle.
    pub fn line_field_lanes_over_azimuth(
        &self,
        first: f64,
        directions: &[WavefrontDirection],
        noise: Option<&NoiseShape>,
    ) -> Option<Vec<f64>> {
        if self.engine.engine() != (Engine::Monochromatic { fft: None })
            || !matches!(self.engine.frequency_rule(), FrequencyRule::Adaptive { .. })
            || !self.direction_dependent()
            || directions.is_empty()
            || !directions.iter().all(|d| matches!(d, WavefrontDirection::FieldAngle(_)))
        {
            return None;
        }
        let (average, _) = self.azimuth_rule_lanes(first, directions, noise, true)?;
        Some(average[1..=directions.len()].to_vec())
    }

    /// `[M̄, lanes…, P_ν]` averaged over azimuth from `first`: along each azimuth the value's
    /// adaptive rule (of `P |O|`, or `P |O|/n` with a noise spectrum), the lanes along
    /// `directions` and then `|O|` recorded at each frequency read and integrated with the
    /// accepted weights (`P_ν` the pixel MTF's term of an integration by parts). The rule over
    /// azimuth is the value's nested trapezoid rule, doubled until the mean and the lanes each
    /// move by at most [`AZIMUTH_SHARE`] of the tolerance relative to the larger of the mean and
    /// the lanes' size (the lanes turn faster with the azimuth than `|O|` does).
    fn azimuth_refined_lanes(
        &self,
        first: f64,
        directions: &[WavefrontDirection],
        noise: Option<&NoiseShape>,
    ) -> Option<(Vec<f64>, Work)> {
        self.azimuth_rule_lanes(first, directions, noise, false)
    }

    /// [`azimuth_refined_lanes`](Self::azimuth_refined_lanes); with `own`, the rule over azimuth
    /// doubles until the lanes move by at most [`AZIMUTH_SHARE`] of the frequency rule's
    /// tolerance relative to the lanes' own size (the mean's left out).
    fn azimuth_rule_lanes(
        &self,
        first: f64,
        directions: &[WavefrontDirection],
        noise: Option<&NoiseShape>,
        own: bool,
    ) -> Option<(Vec<f64>, Work)> {
        let lanes = directions.len();
        let along = |azimuth: f64| -> Option<(Vec<f64>, Work)> {
            *self.gradient.borrow_mut() =
                Some(Recording { lanes, directions: directions.to_vec(), ..Recording::default() });
            let (mean, work) = match noise {
                None => self.mean_of(&|nu| self.recorded_modulus_along(nu, azimuth)),
                Some(shape) => self.mean_of_cut(
                    &|nu| self.over_noise(nu, self.recorded_modulus_along(nu, azimuth), shape),
                    shape.rows(),
                ),
            };
            let r = self.gradient.borrow_mut().take()?;
            if r.failed {
                return None;
            }
            let mut sum = vec![0.0; lanes + 1];
            for &(nu, w) in &r.accepted {
                let &i = r.at.get(&nu.to_bits())?;
                for (g, d) in sum.iter_mut().zip(&r.derivatives[i..i + lanes]) {
                    *g += w * d;
                }
                sum[lanes] += w * r.derivatives[i + lanes] * self.pixel_log_slope(nu);
            }
            let scale = 1.0 / self.scene.max_frequency;
            let mut out = Vec::with_capacity(lanes + 2);
            out.push(mean);
            out.extend(sum.iter().map(|g| g * scale));
            Some((out, work))
        };
        let mut work = Work::default();
        let mut count = self.first_azimuths();
        let mut average = vec![0.0; lanes + 2];
        for k in 0..count {
            let (v, w) = along(first + PI * k as f64 / count as f64)?;
            for (a, v) in average.iter_mut().zip(v) {
                *a += v / count as f64;
            }
            work = add(work, w);
        }
        while count < MAX_AZIMUTHS {
            // the new azimuths halfway between the old ones
            let mut added = vec![0.0; lanes + 2];
            for k in 0..count {
                let (v, w) = along(first + PI * (2 * k + 1) as f64 / (2 * count) as f64)?;
                for (a, v) in added.iter_mut().zip(v) {
                    *a += v;
                }
                work = add(work, w);
            }
            count *= 2;
            let before: Vec<f64> = average[1..=lanes].to_vec();
            let mut change = 0.0f64;
            for (a, add) in average.iter_mut().zip(added) {
                let refined = 0.5 * *a + add / count as f64;
                change = change.max((refined - *a).abs());
                *a = refined;
            }
            let norm = average[1..=lanes].iter().map(|g| g * g).sum::<f64>().sqrt();
            if own {
                // the lanes alone (the pixel MTF's term and the mean not asked), against their
                // own size; lanes 0 by symmetry stop at the first doubling that leaves them so
                let change = (0..lanes).map(|i| (average[i + 1] - before[i]).abs()).fold(0.0, f64::max);
                if change <= AZIMUTH_SHARE * self.asked_tolerance * norm {
                    break;
                }
                continue;
            }
            let size = average[0].abs().max(norm);
            if change <= AZIMUTH_SHARE * self.tolerance() * size {
                break;
            }
        }
        Some((average, work))
    }

    /// The mean MTF along `azimuth` ([`mean_mtf_along`](Self::mean_mtf_along)'s adaptive rule)
    /// and its derivative with respect to each of `directions` on the same rule: each OTF's
    /// derivatives from the engine (`OtfEngine::otf_along_and_gradient`: the exact engine's
    /// field angles, docs/physics.md "Gradients: the field point"), `∂|O| = Re(O* ∂O)/|O|` (0
    /// where `O = 0`), integrated with the accepted panels' nodes and weights (pixel MTF
    /// included). `None` where the rule is not adaptive or the engine gives no derivative.
    pub fn mean_mtf_along_and_gradient(
        &self,
        azimuth: f64,
        directions: &[WavefrontDirection],
    ) -> Option<(f64, Work, Vec<f64>)> {
        self.along_and_gradient(azimuth, directions, None)
    }

    /// [`mean_mtf_along_and_gradient`](Self::mean_mtf_along_and_gradient) under a non-white
    /// noise spectrum `n`: the mean along `azimuth` of `P |O| / n` on the value's rule cut at the
    /// table's rows ([`mean_mtf_over_noise`](Self::mean_mtf_over_noise)'s) and its derivative
    /// along each of `directions`, each `∂|O|` divided by `n(ν)` as the value is (docs/physics.md,
    /// "Gradients under a noise spectrum").
    pub fn mean_mtf_along_over_noise_and_gradient(
        &self,
        azimuth: f64,
        directions: &[WavefrontDirection],
        noise: &NoiseShape,
    ) -> Option<(f64, Work, Vec<f64>)> {
        self.along_and_gradient(azimuth, directions, Some(noise))
    }

    /// The one recording pass of the two above.
    fn along_and_gradient(
        &self,
        azimuth: f64,
        directions: &[WavefrontDirection],
        noise: Option<&NoiseShape>,
    ) -> Option<(f64, Work, Vec<f64>)> {
        if !matches!(self.engine.frequency_rule(), FrequencyRule::Adaptive { .. }) {
            return None;
        }
        let lanes = directions.len();
        *self.gradient.borrow_mut() =
            Some(Recording { lanes, directions: directions.to_vec(), ..Recording::default() });
        let (mean, work) = match noise {
            None => self.mean_of(&|nu| self.recorded_modulus_along(nu, azimuth)),
            Some(shape) => self
                .mean_of_cut(&|nu| self.over_noise(nu, self.recorded_modulus_along(nu, azimuth), shape), shape.rows()),
        };
        let r = self.gradient.borrow_mut().take()?;
        if r.failed {
            return None;
        }
        let mut sum = vec![0.0; lanes];
        for &(nu, w) in &r.accepted {
            let &i = r.at.get(&nu.to_bits())?;
            for (g, d) in sum.iter_mut().zip(&r.derivatives[i..i + lanes]) {
                *g += w * d;
            }
        }
        let scale = 1.0 / self.scene.max_frequency;
        Some((mean, work, sum.into_iter().map(|g| g * scale).collect()))
    }

    /// The pixel MTF's term of an integration by parts in ν,
    ///
    /// ```text
    /// P_ν = (1/ν_max) ∫ ν P′(ν) |O(ν)| dν      (νP′/P = x cot x − 1, x = πpν)
    /// ```
    ///
    /// beside the mean MTF, on the value's own frequency rule (docs/physics.md, "Gradients: the
    /// pixel pitch with the pixel MTF"): `|O|` is recorded at every frequency the rule reads and
    /// the accepted panels' weights (the pixel MTF included) integrate it times `νP′/P`. The
    /// mean is the value's: [`mean_mtf`](Self::mean_mtf)'s for a rotationally symmetric OTF
    /// (bit for bit, the same reads), and [`mean_mtf_over_azimuth`](Self::mean_mtf_over_azimuth)'s
    /// rule over azimuth from `first` where the OTF depends on direction on an adaptive rule (a
    /// 1-D engine's image shifts or tables, the overlap engine, a PSF stack's planes);
    /// `P_ν` is averaged as the mean is; on the FFT path's fixed rule, that rule's, on the
    /// value's sampling levels (`fixed_pixel_slope`). `None` without
    /// the pixel MTF, or where the engine gives no modulus along an azimuth.
    pub fn mean_mtf_and_pixel_slope(&self, first: f64) -> Option<(f64, f64, Work)> {
        self.scene.pixel_pitch?;
        if let FrequencyRule::Fixed { cell } = self.engine.frequency_rule() {
            return self.has_pupil_grid().then(|| self.fixed_pixel_slope(first, cell));
        }
        // the mean over azimuth wherever the OTF depends on direction, as the value's
        if self.has_pupil_grid() || self.direction_dependent() {
            let mut pixel = 0.0;
            let mean = self.azimuthal_mean_with_lanes(first, &[], None, &mut |nu, w, recorded| {
                pixel += w * recorded[0] * self.pixel_log_slope(nu);
            })?;
            let scale = 1.0 / (self.scene.max_frequency * mean.azimuths as f64);
            return Some((mean.mean, pixel * scale, mean.work));
        }
        *self.gradient.borrow_mut() = Some(Recording { lanes: 1, ..Recording::default() });
        let (mean, work) = self.mean_of(&|nu| {
            let v = self.otf(nu);
            self.record(nu, Some(v), &[v])
        });
        let r = self.gradient.borrow_mut().take()?;
        if r.failed {
            return None;
        }
        let mut pixel = 0.0;
        for &(nu, w) in &r.accepted {
            let &i = r.at.get(&nu.to_bits())?;
            // the weight carries the sign of O: w O = P |O| times the rule's weight
            pixel += w * r.derivatives[i] * self.pixel_log_slope(nu);
        }
        Some((mean, pixel / self.scene.max_frequency, work))
    }

    /// [`mean_mtf_and_pixel_slope`](Self::mean_mtf_and_pixel_slope) on the FFT path's grids: the
    /// value's rule over azimuth ([`mean_mtf_over_azimuth`](Self::mean_mtf_over_azimuth), whose
    /// means along each azimuth the grids hold) gives the azimuths; along each, the value's fixed
    /// composite rule over `[0, top]` with `P |O|` times `νP′/P`, on the fine level and, where
    /// the value is the Richardson extrapolation of two levels, on the coarse one too, combined
    /// as the value is (the extrapolation is linear in the two means).
    fn fixed_pixel_slope(&self, first: f64, cell: f64) -> (f64, f64, Work) {
        let mean = self.mean_mtf_over_azimuth(first, None);
        let count = mean.azimuths;
        let top = self.active_top();
        let (panels, _) = super::grid::fixed_rule(top, cell);
        let level = || {
            let along = |azimuth: f64| {
                quad::composite_fixed(0.0, top, panels, |nu| {
                    self.otf_along(nu, azimuth).norm() * self.pixel_factor(nu) * self.pixel_log_slope(nu)
                })
            };
            let sum: f64 = (0..count).map(|k| along(first + PI * k as f64 / count as f64)).sum();
            sum / (count as f64 * self.scene.max_frequency)
        };
        let fine = level();
        let slope = match self.engine.richardson() {
            Some(plan) => {
                self.engine.read_coarse(true);
                let coarse = level();
                self.engine.read_coarse(false);
                plan.extrapolate(coarse, fine).value
            }
            None => fine,
        };
        (mean.mean, slope, mean.work)
    }

    /// `ν P′(ν)/P(ν)` of the pixel MTF `P = |sin x / x|`, `x = πpν` (`x cot x − 1`, its series
    /// near 0); 0 without the pixel MTF.
    fn pixel_log_slope(&self, nu: f64) -> f64 {
        self.scene.pixel_pitch.map_or(0.0, |p| {
            let x = PI * p * nu;
            if x.abs() < 1e-4 { -x * x / 3.0 - x.powi(4) / 45.0 } else { x / x.tan() - 1.0 }
        })
    }

    /// `|O(ν, φ)|` at `nu` along `azimuth` with `∂|O| = Re(O* ∂O)/|O|` for each recorded
    /// direction kept in the recording.
    fn recorded_modulus_along(&self, nu: f64, azimuth: f64) -> f64 {
        let directions = self.gradient.borrow().as_ref().map_or_else(Vec::new, |r| r.directions.clone());
        let mut derivatives = vec![Complex64::new(0.0, 0.0); directions.len()];
        let value = self.engine.otf_along_and_gradient(nu, azimuth, &directions, &mut derivatives);
        let mut recording = self.gradient.borrow_mut();
        let Some(r) = recording.as_mut() else { return value.map_or(f64::NAN, |v| v.norm()) };
        match value {
            Some(v) => {
                let modulus = v.norm();
                let place = r.derivatives.len();
                r.derivatives
                    .extend(derivatives.iter().map(|d| if modulus > 0.0 { (v.conj() * d).re / modulus } else { 0.0 }));
                // |O| itself after the lanes (the pixel MTF's term of the F-number's integration
                // by parts: `mean_mtf_over_azimuth_and_defocus_lane`)
                r.derivatives.push(modulus);
                r.at.insert(nu.to_bits(), place);
                modulus
            }
            None => {
                r.failed = true;
                drop(recording);
                self.otf_along(nu, azimuth).norm()
            }
        }
    }

    /// The MTF at `frequency` averaged over azimuth, `(1/π) ∫_0^π |OTF(ν, φ)| dφ`, by the
    /// nested trapezoid rule of [`mean_mtf_over_azimuth`](Self::mean_mtf_over_azimuth) (to the
    /// same share of the tolerance, absolute), pixel MTF included.
    pub fn mtf_over_azimuth(&self, frequency: f64, first: f64) -> f64 {
        let at = |k: usize, count: usize| self.mtf_along(frequency, first + PI * k as f64 / count as f64);
        let mut count = FIRST_AZIMUTHS;
        let mut average = (0..count).map(|k| at(k, count)).sum::<f64>() / count as f64;
        while count < MAX_AZIMUTHS {
            let added: f64 = (0..count).map(|k| at(2 * k + 1, 2 * count)).sum();
            count *= 2;
            let refined = 0.5 * average + added / count as f64;
            let change = (refined - average).abs();
            average = refined;
            if change <= AZIMUTH_SHARE * self.tolerance() {
                break;
            }
        }
        average
    }

    /// Adaptive mean over `[0, max_frequency]` of `P(ν) |value(ν)|`, where `value` is a signed
    /// OTF (split at its sign changes) or a modulus.
    fn mean_of(&self, value: &dyn Fn(f64) -> f64) -> (f64, Work) {
        self.mean_of_cut(value, &[])
    }

    /// [`mean_of`](Self::mean_of) of an integrand with kinks of its own at `kinks` (cycles/m):
    /// the adaptive rule's intervals are cut there as at the engine's cutoffs, so that each
    /// panel holds a smooth integrand (docs/physics.md, "Gradients under a noise spectrum": a
    /// noise table's rows, where `1/n(ν)` has its kinks). The fixed rule of the FFT path ignores
    /// them (its grid is only continuous anyway).
    fn mean_of_cut(&self, value: &dyn Fn(f64) -> f64, kinks: &[f64]) -> (f64, Work) {
        let mut work = if self.engine.engine() == Engine::ClosedForm {
            Work::default()
        } else {
            let nodes = self.engine.nodes();
            Work {
                spectral_panels: nodes.panels.len(),
                spectral_nodes: nodes.nodes.len(),
                spectral_interpolated: nodes.interpolated,
                ..Work::default()
            }
        };
        if let FrequencyRule::Fixed { cell } = self.engine.frequency_rule() {
            // The interpolated grid is only continuous across its cells (kinks at every grid line
            // of every node): a fixed composite rule at half the finest cell, not an
            // adaptive one, integrates it to well below the FFT path's own error.
            // over [0, highest cutoff] where that is below max_frequency: the OTF is zero beyond
            let top = self.active_top();
            let (panels, evaluations) = super::grid::fixed_rule(top, cell);
            work.frequency_panels = panels;
            work.otf_evaluations = evaluations;
            let mean = || {
                quad::composite_fixed(0.0, top, panels, |nu| value(nu).abs() * self.pixel_factor(nu))
                    / self.scene.max_frequency
            };
            let fine = mean();
            // the sampling chosen from the tolerance: the same mean at N/2, extrapolated
            if let Some(plan) = self.engine.richardson() {
                self.engine.read_coarse(true);
                let coarse = mean();
                self.engine.read_coarse(false);
                work.otf_evaluations += evaluations;
                return (plan.extrapolate(coarse, fine).value, work);
            }
            return (fine, work);
        }
        // The tolerance is relative to the mean, which is not known before it is computed: the
        // first pass assumes a mean of at least `guess`; a smaller result is recomputed with its
        // own value as the guess (absolute error ≤ tolerance × mean, never below 1e-15).
        // Where the highest cutoff lies below max_frequency, the mean is at most the fraction
        // `active` of the range the OTF is non-zero on: the guesses scale with it, and the error
        // budget, spent on that fraction only, is divided by it, so that the tolerance stays
        // relative to the OTF there (a 1e-206 m pixel puts the fraction at 1e-200: the budget of
        // the whole range asked 1e-15 of the OTF, its rounding noise, for 6000 sign changes)
        let active = (self.active_top() / self.scene.max_frequency).clamp(f64::MIN_POSITIVE, 1.0);
        let mut guess = 0.25 * active;
        loop {
            let closed_before = self.engine.value_evaluations();
            let (mean, pass) = self.mean_pass(value, self.frequency_tolerance() * guess / active, kinks);
            work.frequency_panels += pass.frequency_panels;
            work.otf_evaluations += pass.otf_evaluations;
            work.sign_changes += pass.sign_changes;
            let inner = self.engine.value_evaluations() - closed_before;
            if self.engine.engine() == Engine::ClosedForm {
                work.closed_form_evaluations += inner;
            } else {
                work.spectral_evaluations += inner;
            }
            if mean >= 0.5 * guess || guess <= 1e-9 * active {
                return (mean, work);
            }
            guess = mean.max(1e-9 * active);
        }
    }

    /// One adaptive pass of [`mean_of`](Self::mean_of) to an absolute error `absolute` of the mean
    /// over the range where the OTF is non-zero (the whole range unless the highest cutoff is
    /// below `max_frequency`), with the integrand's own `kinks` (cycles/m) among the intervals'
    /// ends.
    fn mean_pass(&self, value: &dyn Fn(f64) -> f64, absolute: f64, kinks: &[f64]) -> (f64, Work) {
        let mut work = Work::default();
        // a new pass reads every value again, to its own tolerance: only its rule counts
        if let Some(r) = self.gradient.borrow_mut().as_mut() {
            r.accepted.clear();
            r.at.clear();
            r.derivatives.clear();
        }
        // each closed-form OTF value may be off by half the budget: the mean is a weighted
        // average of them (and the ν rule below treats differences within that as their noise)
        self.engine.set_value_tolerance(0.5 * absolute);
        // panel errors are budgeted per unit width: Σ tolerance × (b − a) = absolute × ν_max
        let tolerance = absolute;
        let min_panels = match self.engine.frequency_rule() {
            FrequencyRule::Adaptive { min_panels } => min_panels,
            FrequencyRule::Fixed { .. } => 4.0,
        };
        let mut total = 0.0;
        // the nested Clenshaw–Curtis rules where the OTF is smooth in ν by construction
        // (`OtfEngine::smooth_in_frequency`: product-integration nodes, or the closed form
        // where every wavelength of its ±7σ passes the limit); elsewhere (cutoff kinks, the
        // reference panels) the adaptive rule alone
        let smooth_rule = self.engine.smooth_in_frequency(self.scene.max_frequency);
        let top = self.scene.max_frequency;
        let mut cuts = self.engine.frequency_cuts(top);
        cuts.extend(kinks.iter().copied().filter(|&k| k > 0.0 && k < top));
        for pair in super::sort_cuts(cuts).windows(2) {
            let (a, b) = (pair[0], pair[1]);
            // at least 4 panels over the whole range, not per interval between cutoff cuts
            // (1 on the closed-form engine, whose OTF has no kinks)
            let floor = (min_panels * (b - a) / self.scene.max_frequency).ceil();
            // beyond the highest cutoff the OTF is zero: one panel (a range up to 1e199 cycles/m
            // past it, from a 1e-206 m pixel, would otherwise ask for more panels than exist)
            let n = if a >= self.max_cutoff() {
                1
            } else {
                (self.defocus_phase(a, b, self.w020_rms) / quad::MAX_PANEL_PHASE)
                    .ceil()
                    .max(floor)
                    .clamp(1.0, MAX_PANELS) as usize
            };
            // past the averaging frequency's decay (`AVERAGED_DECAY`), `ν |OTF|` is about
            // constant: one panel in ln ν
            let logarithmic = self
                .engine
                .averaged_defocus()
                .is_some_and(|(averaging, _)| a > 0.0 && a >= (1.0 - 1e-9) * AVERAGED_DECAY * averaging);
            let h = (b - a) / n as f64;
            let mut left = (a, value(a));
            work.otf_evaluations += 1;
            for k in 0..n {
                let hi = if k + 1 == n { b } else { a + h * (k + 1) as f64 };
                let right = (hi, value(hi));
                work.otf_evaluations += 1;
                let smooth = if smooth_rule {
                    self.smooth_panel(value, left, right, tolerance, logarithmic, &mut work)
                } else {
                    None
                };
                total += match smooth {
                    Some(integral) => integral,
                    None => self.integrate_panel(value, left, right, tolerance, 0, &mut work),
                };
                left = right;
            }
        }
        (total / self.scene.max_frequency, work)
    }

    /// The defocus phase the OTF turns through over `[a, b]` (radians), with `w020` the defocus
    /// to resolve: its rate in ν is `d/dν [8π F# ν W020 (cos t − ν λ F#)] = 8π F# W020 (cos t − 2s)`,
    /// at most `8π F# |W020|`. Where the engine knows the oscillations to average out over the
    /// spectrum beyond `ν_s` ([`OtfEngine::averaged_defocus`](super::OtfEngine::averaged_defocus)),
    /// `w020` is replaced by the mean defocus plus the spread `|w1| σ = 1/(8π F# ν_s)`, damped as
    /// the averaging damps the oscillation, `exp(−(a/ν_s)²/2)` at the panel's start.
    fn defocus_phase(&self, a: f64, b: f64, w020: f64) -> f64 {
        let rate = 8.0 * PI * self.scene.f_number;
        match self.engine.averaged_defocus() {
            Some((averaging, mean)) => {
                let damping = (-0.5 * (a / averaging).powi(2)).exp();
                (b - a) * (rate * mean.abs() + 1.0 / averaging) * damping
            }
            None => (b - a) * rate * w020,
        }
    }

    /// `∫ P(ν) |OTF_poly(ν)| dν` over one panel where the OTF keeps its sign, by nested
    /// Clenshaw–Curtis rules (9, 17, 33, 65 points; each level's points are the next one's even
    /// points, so climbing wastes no evaluation), or `None` where a sign change shows between
    /// the samples or the rules do not settle (the adaptive rule takes the panel then).
    ///
    /// The error of a level is estimated from the differences between consecutive levels
    /// ([`nested_error`](super::nested_error); for a function analytic near the panel the
    /// Chebyshev coefficients, and with them the error, fall geometrically once the rule resolves
    /// it: Trefethen, ATAP ch. 8 and 19). The ratio is taken between levels of 5 points or more,
    /// so the nested estimate accepts no level below 17 points (the Chebyshev tail below may
    /// accept 9), and a pair that agrees by chance must also follow a fall.
    /// Differences within the engine's own noise per value (closed form) are accepted as such.
    /// `logarithmic`: the points and weights in `u = ln ν` (`∫ f dν = ∫ ν f du`), for the decay
    /// past [`AVERAGED_DECAY`], where `ν |OTF|` is about constant (F/1.4, 200 nm: one panel from
    /// 12 to 96 cycles/mm where an octave each took four).
    fn smooth_panel(
        &self,
        value: &dyn Fn(f64) -> f64,
        left: (f64, f64),
        right: (f64, f64),
        tolerance: f64,
        logarithmic: bool,
        work: &mut Work,
    ) -> Option<f64> {
        let (a, b) = (left.0, right.0);
        // the points and the Jacobian: in ν, or in u = ln ν (dν = ν du)
        let (c, h) = if logarithmic {
            (0.5 * (a.ln() + b.ln()), 0.5 * (b.ln() - a.ln()))
        } else {
            (0.5 * (a + b), 0.5 * (b - a))
        };
        // the end points exactly `a` and `b` (their values are `left` and `right`): in ln ν,
        // exp(ln b) may differ from b in its last bit, and a gradient's recording, which finds
        // each accepted node's derivatives by its frequency, would then miss the end points
        let point = |k: usize, points: usize| {
            if k == 0 {
                return b;
            }
            if k == points - 1 {
                return a;
            }
            let x = c + h * chebyshev_points(points)[k];
            if logarithmic { x.exp() } else { x }
        };
        let budget = tolerance * (b - a);
        let noise = 2.0 * self.engine.value_noise() * (b - a);
        // the signed values at the current level's points, k = 0 at b
        let mut values: Vec<f64> = vec![right.1, left.1];
        let mut previous: Option<f64> = None;
        let mut moves: Vec<f64> = Vec::new();
        // the defocus phase across the panel of the most defocused order that matters, and the
        // points that resolve it (as in the spectral rule): a rule below them may see the
        // oscillation of a far-defocused order of small weight (a harmonic lens's outer orders)
        // as converged
        let resolved = 0.3 * self.defocus_phase(a, b, self.w020_resolved) + 1.0;
        if resolved > 65.0 {
            return None;
        }
        let tail_resolved = 0.5 * self.defocus_phase(a, b, self.w020_resolved) + 1.0;
        // |OTF| P(ν) (× ν in ln ν) at the level's points, k = 0 at b, for its Chebyshev tail
        let mut integrand: Vec<f64> = Vec::with_capacity(65);
        for &points in &[3usize, 5, 9, 17, 33, 65] {
            if points > 3 {
                let old = std::mem::take(&mut values);
                let step = (points - 1) / ((old.len() - 1).max(1));
                values = (0..points)
                    .map(|k| {
                        if k % step == 0 {
                            old[k / step]
                        } else {
                            work.otf_evaluations += 1;
                            value(point(k, points))
                        }
                    })
                    .collect();
            } else {
                work.otf_evaluations += 1;
                values.insert(1, value(point(1, 3)));
            }
            // a sign change: the adaptive rule locates it
            let mut last = 0.0;
            for &v in &values {
                if v != 0.0 {
                    if last * v < 0.0 {
                        return None;
                    }
                    last = v;
                }
            }
            let weights = clenshaw_curtis(points);
            let mut integral = 0.0;
            let mut largest: f64 = 0.0;
            integrand.clear();
            for (k, (&v, &w)) in values.iter().zip(weights).enumerate() {
                let nu = point(k, points);
                let f = v.abs() * self.pixel_factor(nu) * if logarithmic { nu } else { 1.0 };
                largest = largest.max(f);
                integrand.push(f);
                integral += w * h * f;
            }
            if let Some(before) = previous {
                let moved = (integral - before).abs();
                // the next move predicted from the ratio of the last two (geometric convergence),
                // taken between levels of 5 points or more: the 3-point level resolves nothing,
                // and its move makes any ratio after it look fast (F/1.86, 20 nm: moves 1.4e-2
                // then 4.1e-6 credited the 9-point mean with 1.1e-9; it was 1.65e-7 off, over
                // tolerances 1e-7 and 1e-8)
                if points > 5 {
                    moves.push(moved);
                }
                let error = level_error(&moves, points as f64 >= resolved, nested_error);
                // once the level resolves the panel's phase (0.5 points a radian), the tail of
                // its own Chebyshev coefficients bounds the rule's error (module `quad`'s test:
                // the tail times the constant weight's largest moment from degree (n − 1)/2 up,
                // 2/(((n − 1)/2)² − 1), times the half-width), which credits the super-geometric
                // fall the nested estimate cannot see: the Binary 2 metalens at 1e-6 accepted at
                // 17 points where the nested estimate asked for 33 (its 17-point mean 2.5e-8 off)
                let tail_error = if points >= 9 && points as f64 >= tail_resolved {
                    let half = ((points - 1) / 2) as f64;
                    quad::chebyshev_tail(&integrand) * 2.0 / (half * half - 1.0) * h
                } else {
                    f64::INFINITY
                };
                if error <= budget
                    || tail_error <= budget
                    || moved <= noise
                    || moved <= 1e3 * f64::EPSILON * largest * (b - a)
                {
                    work.frequency_panels += 1;
                    if self.recording() {
                        for (k, (&v, &w)) in values.iter().zip(weights).enumerate() {
                            let nu = point(k, points);
                            let jacobian = if logarithmic { nu } else { 1.0 };
                            self.accept(nu, w * h * self.pixel_factor(nu) * jacobian * sign(v));
                        }
                    }
                    return Some(integral);
                }
            }
            previous = Some(integral);
        }
        None
    }

    /// `∫ P(ν) |OTF_poly(ν)| dν` over one panel whose end values are known: split at sign
    /// changes, bisected until the Gauss–Kronrod error estimate is below `tolerance × width`.
    fn integrate_panel(
        &self,
        value: &dyn Fn(f64) -> f64,
        left: (f64, f64),
        right: (f64, f64),
        tolerance: f64,
        depth: u32,
        work: &mut Work,
    ) -> f64 {
        let (a, b) = (left.0, right.0);
        let half = 0.5 * (b - a);
        let mut samples = [(0.0, 0.0); 17];
        samples[0] = left;
        samples[16] = right;
        let nodes = quad::GK15.nodes(a, b);
        for (i, &nu) in nodes[..15].iter().enumerate() {
            samples[i + 1] = (nu, value(nu));
        }
        work.otf_evaluations += 15;
        // sign changes between consecutive non-zero samples (exact zeros, e.g. past the cutoff
        // where the OTF vanishes identically, are not sign changes)
        let mut edges = Vec::new();
        let mut last: Option<(f64, f64)> = None;
        for &(x, f) in &samples {
            if f == 0.0 {
                continue;
            }
            if let Some((x0, f0)) = last
                && f0 * f < 0.0
            {
                // a zero of OTF_poly (Illinois), to 1e-14 of the frequency limit (or of the highest cutoff)
                let mut counted = |nu: f64| {
                    work.otf_evaluations += 1;
                    value(nu)
                };
                let zero = quad::illinois(&mut counted, x0, f0, x, f, 1e-14 * self.active_top());
                edges.push((zero, 0.0));
            }
            last = Some((x, f));
        }
        if !edges.is_empty() && depth < MAX_DEPTH {
            work.sign_changes += edges.len();
            let mut total = 0.0;
            let mut from = left;
            for to in edges.into_iter().chain(std::iter::once(right)) {
                total += self.integrate_panel(value, from, to, tolerance, depth + 1, work);
                from = to;
            }
            return total;
        }
        let mut values = [0.0; 15];
        for (v, &(nu, f)) in values.iter_mut().zip(&samples[1..16]) {
            *v = f.abs() * self.pixel_factor(nu);
        }
        let panel = quad::GK15.sums(half, &values);
        let kronrod = panel.kronrod;
        // Accept at the tolerance, or where no refinement can help: the Kronrod–Gauss difference
        // at the rounding level of the sums themselves (near the cutoff the OTF is tiny and its
        // evaluation noise does not shrink with the panel), or a panel below 1e-9 of the range.
        let rounding = 1e3 * f64::EPSILON * kronrod.abs().max(tolerance * (b - a));
        // closed-form OTF values are themselves computed to `otf_tolerance`: a Kronrod–Gauss
        // difference within twice that per unit width is their noise, which no bisection removes
        // (at thousands of waves the rule otherwise bisected at the noise level without end)
        let noise = 2.0 * self.engine.value_noise() * (b - a);
        // QUADPACK's estimate: the asymptotic one (|K − G|^1.64 of the variation, trusted below
        // 1e-3 of it) accepted a panel holding a hidden dip of the OTF to zero, 180× over the
        // tolerance (F/12.9, 21.5 nm, 2 µm pixels; test closed_form_engine_meets_the_requested_tolerance)
        let error = panel.error();
        if error <= tolerance * (b - a)
            || error <= rounding
            || (panel.kronrod - panel.gauss).abs() <= noise
            || b - a <= 1e-9 * self.active_top()
            || depth >= MAX_DEPTH
        {
            work.frequency_panels += 1;
            if self.recording() {
                let weights = quad::GK15.kronrod_weights();
                for (&(nu, f), &w) in samples[1..16].iter().zip(&weights) {
                    self.accept(nu, half * w * self.pixel_factor(nu) * sign(f));
                }
            }
            return kronrod;
        }
        let centre = samples[8];
        self.integrate_panel(value, left, centre, tolerance, depth + 1, work)
            + self.integrate_panel(value, centre, right, tolerance, depth + 1, work)
    }

    /// The mean MTF as the value takes it and, in the same pass, a lane the caller gives:
    ///
    /// ```text
    /// (1/ν_max) ∫ P(ν) L(ν, φ) dν        (averaged over azimuth as the mean is)
    /// ```
    ///
    /// `lane(ν, φ)` is the derivative of `|O(ν, φ)|` (`φ` from the x axis) the caller knows at
    /// each frequency the rule reads: a line on one tabulated order, whose `|O|` is the table's
    /// `|T(c, ν, φ)|` and moves as `sign(T) ∂T/∂c` (docs/physics.md, "Gradients: a line's
    /// wavelength and a blackbody's temperature", on a table). Integrated with the frequency
    /// rule's accepted weights (split at the OTF's sign changes, `P` included; with `noise`,
    /// each weight divided by `n(ν)`, on the value's cut at the noise table's rows), on the
    /// nested rule over azimuth from `first` where the OTF depends on direction, as the value's
    /// ([`mean_mtf_over_azimuth`](Self::mean_mtf_over_azimuth)). Returns `(mean, lane, work)`.
    /// `None` on the FFT path's fixed rule.
    pub fn mean_mtf_and_modulus_lane(
        &self,
        first: f64,
        noise: Option<&NoiseShape>,
        lane: &dyn Fn(f64, f64) -> f64,
    ) -> Option<(f64, f64, Work)> {
        if !matches!(self.engine.frequency_rule(), FrequencyRule::Adaptive { .. }) {
            return None;
        }
        if !(self.has_pupil_grid() || self.direction_dependent()) {
            // the signed OTF: the accepted weights carry sign(O), so the lane is recorded times it
            *self.gradient.borrow_mut() = Some(Recording { lanes: 1, ..Recording::default() });
            let signed = |nu: f64| {
                let v = self.otf(nu);
                self.record(nu, Some(v), &[sign(v) * lane(nu, 0.0)])
            };
            let (mean, work) = match noise {
                None => self.mean_of(&signed),
                Some(shape) => self.mean_of_cut(&|nu| self.over_noise(nu, signed(nu), shape), shape.rows()),
            };
            let recording = self.gradient.borrow_mut().take()?;
            let (mean, found, work) = self.integrate_recorded(mean, recording, work)?;
            return Some((mean, found[0], work));
        }
        let (mut sum, mut failed, mut read) = (0.0, false, 0usize);
        let mean = self.azimuthal_mean(first, &mut |azimuth: f64| {
            *self.gradient.borrow_mut() = Some(Recording { lanes: 1, ..Recording::default() });
            let modulus = |nu: f64| {
                let v = self.otf_along(nu, azimuth).norm();
                self.record(nu, Some(v), &[lane(nu, azimuth)])
            };
            let (mean, work) = match noise {
                None => self.mean_of(&modulus),
                Some(shape) => self.mean_of_cut(&|nu| self.over_noise(nu, modulus(nu), shape), shape.rows()),
            };
            match self.gradient.borrow_mut().take() {
                Some(r) if !r.failed => {
                    for &(nu, w) in &r.accepted {
                        match r.at.get(&nu.to_bits()) {
                            Some(&i) => sum += w * r.derivatives[i],
                            None => failed = true,
                        }
                    }
                }
                _ => failed = true,
            }
            read += 1;
            (mean, work)
        });
        (!failed && read == mean.azimuths)
            .then(|| (mean.mean, sum / (self.scene.max_frequency * mean.azimuths as f64), mean.work))
    }

    /// The end of the frequency range where the OTF can be non-zero: `max_frequency`, or the
    /// highest cutoff if that is below it (the frequency rule's lengths scale with it: a 1e-206 m
    /// pixel puts `max_frequency` 1e200 times above it).
    fn active_top(&self) -> f64 {
        self.max_cutoff().min(self.scene.max_frequency)
    }

    /// Cutoff frequency (cycles/m) of the shortest wavelength covered: `OTF_poly` is zero beyond.
    pub fn max_cutoff(&self) -> f64 {
        self.engine.max_cutoff()
    }
}

/// The derivative of `|x|`: `sign(x)`, 0 at 0 (a kink the frequency rule puts at a panel's end).
fn sign(x: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// `cos(πk/(points − 1))`, k = 0..points, for `points` one of [`CLENSHAW_CURTIS_POINTS`]: the
/// Chebyshev–Lobatto points of [`smooth_panel`](Polychromatic::smooth_panel)'s levels on
/// [−1, 1], each computed once by that expression (the same bits as computing it at each
/// point, which cost two cosines a point and level).
fn chebyshev_points(points: usize) -> &'static [f64] {
    static POINTS: std::sync::OnceLock<Vec<Vec<f64>>> = std::sync::OnceLock::new();
    let all = POINTS.get_or_init(|| {
        CLENSHAW_CURTIS_POINTS
            .iter()
            .map(|&m| (0..m).map(|k| (std::f64::consts::PI * k as f64 / (m - 1) as f64).cos()).collect())
            .collect()
    });
    let index = CLENSHAW_CURTIS_POINTS.iter().position(|&m| m == points).unwrap_or(0);
    &all[index]
}

/// The point counts [`clenshaw_curtis`] has weights for.
pub(crate) const CLENSHAW_CURTIS_POINTS: [usize; 7] = [3, 5, 9, 17, 33, 65, 129];

/// Clenshaw–Curtis weights on [−1, 1] at the `points` Chebyshev–Lobatto points
/// `cos(πk/(points − 1))` (one of [`CLENSHAW_CURTIS_POINTS`]): the product-integration weights of the
/// constant weight, whose Chebyshev moments are `∫ T_j = 2/(1 − j²)` for even j, 0 for odd.
pub(crate) fn clenshaw_curtis(points: usize) -> &'static [f64] {
    static RULES: std::sync::OnceLock<Vec<Vec<f64>>> = std::sync::OnceLock::new();
    let rules = RULES.get_or_init(|| {
        CLENSHAW_CURTIS_POINTS
            .iter()
            .map(|&m| {
                let mu: Vec<f64> =
                    (0..m).map(|j| if j % 2 == 0 { 2.0 / (1.0 - (j * j) as f64) } else { 0.0 }).collect();
                super::spectral::lobatto_weights(&mu, m)
            })
            .collect()
    });
    let index = CLENSHAW_CURTIS_POINTS.iter().position(|&m| m == points).unwrap_or(0);
    &rules[index]
}
