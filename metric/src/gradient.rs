//! The gradient of the ASNR, mean MTF, SNR0 and photoelectrons with respect to scene quantities
//! (docs/physics.md, "Gradients"), from the evaluation's own numbers: no finite differences.
//!
//! `ASNR = SNR0 · G` with `G` the mean MTF (or its mean over a non-white noise spectrum, or the
//! MTF integral for `form = "integral"`), so `∂ASNR = ∂SNR0 · G + SNR0 · ∂G`. The radiometric,
//! exposure and sensor quantities change `N`, the stray light and the noise terms only:
//! `∂SNR0` follows from [`noise::NoiseBudget::snr_partials`], and `∂G = 0` because the OTF's
//! spectral weights are normalized (a factor constant in λ leaves them as they are). The pixel
//! pitch also moves the Nyquist frequency: `M̄ = (1/ν_N) ∫_0^{ν_N} |O| dν`, so by Leibniz'
//! rule `∂M̄/∂ν_N = (MTF(ν_N) − M̄)/ν_N`, one OTF value at ν_N.

use noise::SnrPartials;

use crate::evaluate::{
    BiasLanes, DefocusFound, DefocusLane, Evaluation, GridGradient, evaluate_field_differentiated,
    evaluate_field_with_lanes, mtf_at,
};
use crate::{Error, GlareMode, MetricForm, Scene};

mod achromat;
mod library_fft;
mod line_grids;
mod line_table;
mod map;
mod multiplexed;
mod noise_weight;
mod segmented;

pub use multiplexed::{channel_efficiency_gradient, channel_gradients, channel_wavelength_gradient};
pub use segmented::zone_key_gradient;

/// A scene quantity the ASNR can be differentiated against, and what each derivative is taken
/// with respect to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Parameter {
    /// A factor constant in wavelength on the radiance before the lens (a flat source's radiance,
    /// a blackbody's scale, a constant quantum efficiency, the spectrum's peak transmission): the
    /// signal and the stray light are proportional to it. Derivative per relative change,
    /// `∂/∂ln s`.
    SignalScale,
    /// The exposure time t: signal, stray light and dark charge are proportional to it. `∂/∂ln t`.
    Exposure,
    /// A constant imaging efficiency τ1: the signal is proportional to it, the transmitted light
    /// `N_T` (paper SI eq. S14) is not. `∂/∂ln τ1`.
    Efficiency,
    /// A constant total transmission T: `N_T` is proportional to it (it matters only with
    /// `glare = "included"`). `∂/∂ln T`.
    Transmission,
    /// The read noise σ_r: `∂/∂σ_r`, per e⁻ rms.
    ReadNoise,
    /// The dark current: `∂/∂(dark current)`, per e⁻/s.
    DarkCurrent,
    /// The conversion gain K (quantization noise `(1/12)/K²`): `∂/∂K`, per DN/e⁻.
    Gain,
    /// The pixel pitch p: `N ∝ p²` and `ν_N = 1/(2p)`. `∂/∂ln p`. With the pixel MTF `P`, whose
    /// sinc stays in `x = ν/ν_N`, by parts `∂M̄/∂ln p = M̄ − P(ν_N)|O(ν_N)| + P_ν` (docs/physics.md,
    /// "Gradients: the pixel pitch with the pixel MTF"). Under a non-white noise spectrum `n(ν)`
    /// (fixed in cycles/mm: the pitch moves the integral's upper limit only), Leibniz' rule with
    /// `MTF(ν_N)/n(ν_N)` at the limit. Refused with both (the sinc moves in `ν/ν_N`, the noise in
    /// cycles/mm).
    PixelPitch,
    /// The lens's Binary 2 coefficient `A_{i+1}` (`lens.binary2[i]`, radians): it moves the
    /// wavefront of every order (`optics::LensModel::binary2_directions`), so the OTF, not the
    /// photon count. `∂/∂A`, per radian. On axis, on the radial engine (the pixel MTF in the
    /// frequency rule's weights where the camera applies it); under a noise spectrum on the
    /// value's noise-weighted pass (docs/physics.md, "Gradients under a noise spectrum").
    Binary2(usize),
    /// A knot of the lens's freeform phase spline (`lens.phase_spline_rad[i]`, radians): the
    /// profile is linear in its knots, so the knot moves each order's wavefront along the
    /// spline's cardinal basis function times the order's path per radian. The index is the
    /// knot's lane among the lens's wavefront directions (after the Binary 2 coefficients:
    /// `optics::LensModel::binary2_directions`). `∂/∂φ_i`, per radian; where `Binary2` applies.
    PhaseSpline(usize),
    /// An `m = 0` Zernike coefficient of the lens (`lens.zernike_noll_rms_um[j − 1]` for Noll
    /// `j` = 1, 4, 11, 22, …, µm RMS): it adds `√(n+1) R_n^0(ρ)` to every order's wavefront. The
    /// index is its lane among the lens's wavefront directions (after the Binary 2 coefficients
    /// and the spline's knots). `∂/∂c`, per µm; where `Binary2` applies.
    Zernike(usize),
    /// The Zernike coefficient of Noll index `j` (`lens.zernike_noll_rms_um[j − 1]`, µm RMS) of
    /// any lens family that takes Zernike terms, where the OTF is 2-D (a term with `m ≠ 0`, or
    /// the `m = 0` terms of a pupil made 2-D by such a term or by an oblique field): `∂W = 10⁻⁶
    /// Z_j(x, y)` on every order, differentiated by forward mode on the overlap engine's nodes
    /// where every order is the full circle with Seidel and Zernike terms (docs/physics.md,
    /// "Zernike terms on the overlap engine"), else through the FFT ("Gradients: 2-D pupils"). `∂/∂c`, per µm. Where the OTF is
    /// rotationally symmetric on axis (every `m ≠ 0` coefficient zero), a term with `m ≠ 0` has
    /// derivative 0 by symmetry: the term and its negative are one pupil turned by `π/|m|`,
    /// whose mean over azimuth is the same.
    ZernikeNoll(usize),
    /// The lens's F-number F# (`lens.f_number`), focal length held: `∂/∂ln F#`. It scales the
    /// photon count as `NA² = 1/(4F#²)` (SI eq. S7), each wavelength's normalized frequency
    /// `s = νλF#` and the defocus `W020 ∝ f0/F#²` of a lens whose every order is the full
    /// circular pupil with a defocus alone (the chromatic, refractive and harmonic families:
    /// docs/physics.md, "Gradients"; off axis on the exact 1-D engine with the lateral colour's
    /// lane beside, "Gradients: the F-number and the focal length off axis"), or with Seidel
    /// terms under a band on the overlap
    /// engine (the defocus lane on its nodes: "Gradients: the F-number and the focal length
    /// with Seidel terms"); for a lens that gives its aperture directions
    /// (`optics::LensModel::aperture_directions`: a phase lens) the aperture radius
    /// `R = f0/(2F#)` moving its profile and reference sphere, on the radial engine's lanes (off
    /// axis at a single field point on the FFT path's, the oblique wave's path moving too:
    /// docs/physics.md, "Gradients: the F-number and the focal length of a phase lens off axis").
    FNumber,
    /// The lens's focal length f0 (`lens.focal_length_mm`), F-number held: `∂/∂ln f0`. It scales
    /// the defocus `W020 ∝ f0/F#²` only (the cutoff `1/(λF#)` and `NA` stay); where
    /// [`FNumber`](Parameter::FNumber) applies.
    FocalLength,
    /// The centre `c` of the scene's Gaussian spectrum (`spectrum.center_nm`): `∂/∂c`, per m. It
    /// moves the photon count and the OTF's spectral weights (docs/physics.md, "Gradients"). Of a
    /// line, its wavelength: the photon count through the detected spectrum's factors at `c`,
    /// and each order's OTF at `c` (docs/physics.md, "Gradients: a line's wavelength").
    SpectrumCenter,
    /// The spectral range `r = 2√2 σ` of the scene's Gaussian spectrum (`spectrum.range_nm`),
    /// peak held: `∂/∂r`, per m. Of a top-hat, its full width; of a line, its equivalent width
    /// (the photon count alone, `∂ln N/∂r = 1/r`).
    SpectrumRange,
    /// The temperature T of the scene's blackbody source (`source.temperature_k`): `∂/∂T`, per
    /// K. Planck's `∂ln B/∂T` moves the photon count and, over a band, the OTF's spectral
    /// weights (the OTF of `ρ ∂ln B/∂T` on its own engine, for a rotationally symmetric OTF);
    /// under a line the photon count alone (docs/physics.md, "Gradients: a line's wavelength and
    /// a blackbody's temperature").
    Temperature,
    /// A Seidel term of the chromatic lens (`lens.spherical_um`, `lens.coma_um`,
    /// `lens.astigmatism_um`, `lens.field_curvature_um`): `∂/∂W`, per µm. Where the scene's
    /// orders are the full circle with Seidel terms (the overlap engine), forward mode on the
    /// overlap quadrature (docs/physics.md, "Gradients: Seidel terms on the overlap engine").
    /// With every Seidel term zero the OTF is on the 1-D engines: coma's derivative is 0 by
    /// symmetry there (`W131` and `−W131` are one pupil turned by π), spherical aberration's and
    /// field curvature's are taken on the overlap engine with the terms at zero, astigmatism's is
    /// half field curvature's (`x² = ρ²/2 + ρ² cos 2φ/2`; docs/physics.md, "Gradients: Seidel
    /// terms at zero").
    Seidel(optics::SeidelTerm),
    /// The field angle of the scene's single field point along x (`0`, `field.x_deg`) or y
    /// (`1`, `field.y_deg`): `∂/∂θ`, per radian. It moves the relative illumination (a factor on
    /// N and N_T) and, for a lens whose orders change with the field only through their image
    /// shifts (`optics::LensModel::image_shift_field_rates`: the chromatic lens's lateral colour),
    /// each wavelength's OTF phase `exp(−2πi ν·Δ(λ))`: on the exact 1-D engine (off axis, no
    /// Seidel terms) and the overlap engine (Seidel terms), forward mode on their nodes; on axis
    /// with a rotationally symmetric pupil, 0 by symmetry (docs/physics.md, "Gradients: the field point").
    FieldAngle(usize),
    /// The field angle along x (`axis` 0, `fields[point].x_deg`) or y (1, `fields[point].y_deg`)
    /// of one point of a field-of-view list (`[[fields]]`), per radian: the value is the
    /// weighted mean of the points' (fixed weights), so its derivative is that point's
    /// [`FieldAngle`](Parameter::FieldAngle) derivative times its weight over the weights' sum,
    /// and 0 from the other points.
    FieldPointAngle {
        /// The point's place in the list (0-based).
        point: usize,
        /// 0 for x, 1 for y.
        axis: usize,
    },
    /// The bias of a meta-atom library lens's parameter `i` (`lens.parameter_bias[i]`, in the
    /// library's units): every atom's parameter `p_i → p_i + b`, which moves each wavelength's
    /// imaging order (its efficiency τ1, pupil amplitude and wavefront) and the transmission T
    /// (`optics::LensModel::order_derivatives`). `∂/∂b`, per unit of the parameter. On axis,
    /// with a white noise spectrum (docs/physics.md, "Gradients: a library's parameter bias").
    LibraryBias(usize),
    /// The decentre of the lens's circular iris along x (`0`, `lens.iris_decentre_x`) or y (`1`,
    /// `lens.iris_decentre_y`), per unit of the decentre (a fraction of the aperture's radius).
    /// On an order whose only aberration is defocus the iris is the centred circle with a tilt
    /// that moves the image by `Δ = 2 W020 d/NA` (`optics::fft::reduce_decentred_circle`): the
    /// decentre moves each wavelength's OTF phase `exp(−2πi ν·Δ)` only, a lane of the exact 1-D
    /// engine as the field angle's lateral colour is; the photon count does not move (the iris
    /// keeps its area). Where the OTF is rotationally symmetric (the iris centred, on axis) the
    /// derivative is 0 by the mirror symmetry `d → −d` (docs/physics.md, "Gradients: the iris").
    IrisDecentre(usize),
    /// The sample pitch p of a PSF-stack lens (`lens.psf_pitch_um`): the stack is the PSF at
    /// the detector sampled at `x = j p`, so the pitch scales the whole PSF (its centroids too)
    /// and every wavelength's OTF as `O_p(ν) = O(ν p/p0)`; the photon count does not move (each
    /// slice is normalized). The mean MTF over `[0, ν_N]` of an OTF in `νp`, by the change of
    /// variables `u = νp/p0`: `∂M̄/∂ln p = MTF(ν_N) − M̄` (the MTF at Nyquist averaged over azimuth
    /// as `M̄` is), `∂I/∂ln p = ν_N ∂M̄/∂ln p` in the integral form; with the pixel MTF (its sinc
    /// does not scale with p) `P(ν_N)|O(ν_N)| − M̄ − P_ν` by parts. `∂/∂ln p`. Under a noise
    /// spectrum the weighted mean's `P(ν_N)|O(ν_N)|/n(ν_N) − G − (1/ν_N) ∫ P|O|(νP′/P − νn′/n)/n dν`
    /// (docs/physics.md, "Gradients: chain rules", a PSF stack).
    PsfPitch,
    /// The obscuration ε of the chromatic lens's annular iris (`lens.obscuration`, the inner
    /// radius in units of the aperture's), per unit ε, where `0 < ε < 1`: the pupil's inner edge
    /// moves on the FFT path (`optics::WavefrontDirection::Obscuration`: each edge pixel's area
    /// fraction by minus the inner circle's arc length in it, through the autocorrelation and
    /// its normalization; docs/physics.md, "Gradients: the edge's motion on the FFT path"). The
    /// mean MTF's part only: the photon count's, `∂ln N/∂ε = ∂ln N_T/∂ε = −2ε/(1 − ε²)` (the
    /// area fraction on τ1 and T), is the chain rule of the scene's key on
    /// [`Efficiency`](Parameter::Efficiency) and [`Transmission`](Parameter::Transmission).
    Obscuration,
    /// The lens's design wavelength λ0 (`lens.design_wavelength_nm`), per relative change,
    /// `∂/∂ln λ0`: for a lens whose every order is the full circular pupil with a defocus alone
    /// and gives its rates ([`optics::LensModel::design_wavelength_rates`]: the chromatic lens's
    /// `W020 = (1 − λ/λ0) f0/(8F#²)`, the refractive lens's `n0 = n(λ0)`, the harmonic lens's
    /// orders' defocus and efficiencies): each wavelength's defocus moves along its own
    /// `∂W020/∂ln λ0` (not in proportion to `W020`, so not the focal length's lane), and the
    /// orders' efficiencies with it (docs/physics.md, "Gradients: the design wavelength"); off
    /// axis the lateral colour too, as its own scale plus a common translation (docs/physics.md,
    /// "Gradients: the design wavelength off axis"); under a noise spectrum with each
    /// frequency's weight divided by `n(ν)`.
    DesignWavelength,
    /// An edge of the lens's design band (`lens.design_band_nm[i]` of a dispersion-engineered
    /// lens; 0 the short end, 1 the long end), per m, the band's centre held: outside the band
    /// the lens images nothing, so the edge is a limit of the signal's integrals over λ
    /// (Leibniz's rule, as a top-hat spectrum's edge; docs/physics.md, "Gradients: the
    /// dispersion-engineered lens"). The centre's own part is [`DesignWavelength`](Parameter::DesignWavelength)'s.
    BandEdge(usize),
    /// The cell pitch p of a designer's phase map (`lens.phase_map_pitch_um`), per relative
    /// change, `∂/∂ln p`, on axis: the cells' edges move across the pupil (units of the aperture
    /// radius) and each cell's centre with its reference sphere and design-order share, a
    /// complex lane of the field on the FFT path (`optics::WavefrontDirection::MapScale`;
    /// docs/physics.md, "Gradients: a phase map's pitch and aperture"). The photon count does
    /// not move.
    MapPitch,
}

impl Parameter {
    /// The lane among the lens's wavefront directions (`optics::LensModel::binary2_directions`)
    /// of a parameter that moves the wavefront: Binary 2 coefficients, spline knots and `m = 0`
    /// Zernike terms.
    pub fn lane(self) -> Option<usize> {
        match self {
            Parameter::Binary2(i) | Parameter::PhaseSpline(i) | Parameter::Zernike(i) => Some(i),
            _ => None,
        }
    }

    /// The direction a wavefront parameter moves the wavefront in, for the gradient on the FFT
    /// path: a lane of the lens's wavefront directions, or a Zernike term by its Noll index.
    pub fn grid_direction(self) -> Option<optics::WavefrontDirection> {
        match self {
            Parameter::ZernikeNoll(j) => Some(optics::WavefrontDirection::Zernike(j)),
            Parameter::Seidel(t) => Some(optics::WavefrontDirection::Seidel(t)),
            Parameter::FieldAngle(a) => Some(optics::WavefrontDirection::FieldAngle(a)),
            Parameter::IrisDecentre(a) => Some(optics::WavefrontDirection::IrisDecentre(a)),
            Parameter::Obscuration => Some(optics::WavefrontDirection::Obscuration),
            Parameter::MapPitch => Some(optics::WavefrontDirection::MapScale(optics::map::MapScale::Pitch)),
            p => p.lane().map(optics::WavefrontDirection::Lane),
        }
    }

    /// What the derivative is taken against, for messages and docs.
    pub fn describe(self) -> &'static str {
        match self {
            Parameter::SignalScale => "a factor on the detected radiance",
            Parameter::Exposure => "the exposure time",
            Parameter::Efficiency => "a constant imaging efficiency",
            Parameter::Transmission => "a constant total transmission",
            Parameter::ReadNoise => "the read noise",
            Parameter::DarkCurrent => "the dark current",
            Parameter::Gain => "the conversion gain",
            Parameter::PixelPitch => "the pixel pitch",
            Parameter::Binary2(_) => "a Binary 2 coefficient of the lens's phase",
            Parameter::PhaseSpline(_) => "a knot of the lens's phase spline",
            Parameter::Zernike(_) => "an m = 0 Zernike coefficient of the lens",
            Parameter::ZernikeNoll(_) => "a Zernike coefficient of the lens",
            Parameter::Seidel(_) => "a Seidel coefficient of the lens",
            Parameter::FieldAngle(_) => "a field angle",
            Parameter::FieldPointAngle { .. } => "a field angle of a point of the field-of-view list",
            Parameter::SpectrumCenter => "the spectrum's centre (a line's wavelength)",
            Parameter::SpectrumRange => "the spectrum's range (a line's equivalent width)",
            Parameter::Temperature => "the blackbody's temperature",
            Parameter::FNumber => "the lens's F-number",
            Parameter::FocalLength => "the lens's focal length",
            Parameter::LibraryBias(optics::ATOM_PHASE_ERROR) => "the σ of a library lens's atoms' phase errors",
            Parameter::LibraryBias(optics::ATOM_TRANSMISSION_ERROR) => {
                "the σ of a 2-D library layout's atoms' amplitude errors"
            }
            Parameter::LibraryBias(_) => "a library lens's parameter bias",
            Parameter::PsfPitch => "a PSF stack's sample pitch",
            Parameter::IrisDecentre(_) => "the decentre of the lens's iris",
            Parameter::Obscuration => "the obscuration of the lens's iris",
            Parameter::DesignWavelength => "the lens's design wavelength",
            Parameter::BandEdge(_) => "an edge of the lens's design band",
            Parameter::MapPitch => "the cell pitch of the lens's phase map",
        }
    }
}

/// The place of the Zernike term of Noll index `noll` among the `m = 0` terms the lens's wavefront
/// directions follow (Noll 1, 4, 11, 22, … in order: [`Parameter::Zernike`]), or its `(n, m)`
/// where `m ≠ 0` (a term whose OTF depends on direction, not on the radial engine).
pub fn zernike_m0_place(noll: usize) -> Result<usize, (usize, i64)> {
    match optics::fft::noll_to_nm(noll) {
        (_, 0) => Ok((1..noll).filter(|&j| optics::fft::noll_to_nm(j).1 == 0).count()),
        nm => Err(nm),
    }
}

/// The evaluation and its derivatives, one entry per [`Parameter`] asked, in their order (each
/// taken as its parameter says: `∂/∂ln` for the scales, per unit for the noise terms).
#[derive(Clone, Debug, PartialEq)]
pub struct Gradient {
    /// The evaluation the derivatives are taken at ([`crate::evaluate`]'s numbers).
    pub evaluation: Evaluation,
    /// `∂ASNR` (in the scene's form).
    pub asnr: Vec<f64>,
    /// `∂` mean MTF.
    pub mean_mtf: Vec<f64>,
    /// `∂SNR0`.
    pub snr0: Vec<f64>,
    /// `∂N`, photoelectrons.
    pub photoelectrons: Vec<f64>,
}

/// The evaluation of `scene` ([`crate::evaluate`]) and the derivatives of its ASNR, mean MTF,
/// SNR0 and photoelectrons with respect to each of `parameters`. Over a field-of-view average,
/// the weighted mean of each point's derivatives, as the value is the weighted mean of the
/// points'.
///
/// # Errors
/// The evaluation's errors, and [`Error::NotDifferentiable`] where the value is not smooth in a
/// parameter there: a saturated pixel (the charges are clipped), the pixel pitch with both the
/// pixel MTF and a noise spectrum, the conversion gain without an ADC; under a noise spectrum, a
/// key whose noise-weighted lane is not computed (docs/physics.md, "Gradients under a noise
/// spectrum").
pub fn gradient(scene: &Scene, parameters: &[Parameter]) -> Result<Gradient, Error> {
    // the F-number and focal length of a lens that gives its aperture directions (a phase
    // lens): three more lanes of the radial engine, on a lens that appends them
    // and a line's wavelength on a lens that gives its wavelength directions (a phase lens):
    // one more lane per term of the wavefront's rate
    let aperture = parameters.iter().find(|p| matches!(p, Parameter::FNumber | Parameter::FocalLength)).copied();
    let wavelength = parameters.contains(&Parameter::SpectrumCenter);
    let lanes = ExtraLanes::of(scene, aperture, wavelength)?;
    let (scene, bases) = match &lanes {
        Some((wrapped, bases)) => (wrapped, *bases),
        None => (scene, LaneBases::default()),
    };
    let binary2 =
        bases.aperture.is_some() || bases.wavelength.is_some() || parameters.iter().any(|p| p.lane().is_some());
    // the wavefront directions for the FFT path, one per wavefront parameter in their order
    let mut grid: Vec<optics::WavefrontDirection> = parameters.iter().filter_map(|p| p.grid_direction()).collect();
    // the F-number's defocus lane on the overlap engine's own pass, after them (read back by
    // `aperture_on_overlap`)
    if aperture.is_some() && bases.aperture.is_none() && defocus_lane_on_overlap(scene) {
        grid.push(optics::WavefrontDirection::Defocus);
    }
    // a phase lens's aperture lanes off axis on the FFT path, after them (read back by
    // `aperture_lane_partials`)
    if let (Some(base), true) = (bases.aperture, bases.aperture_on_grid > 0) {
        grid.extend(aperture_grid_directions(base, bases.aperture_on_grid > 3));
    }
    // a library lens's parameters whose bias is asked, in their order: their lanes ride on the
    // value's own rules where the engine gives them
    let bias: Vec<usize> =
        parameters.iter().filter_map(|p| if let Parameter::LibraryBias(i) = p { Some(*i) } else { None }).collect();
    if scene.fields().is_empty() {
        // one pass: the evaluation and the wavefront derivatives of its mean MTF together (and
        // the defocus or order lane of a line, or of the F-number, where the engine gives it)
        let lane = defocus_lane(scene, parameters, bases);
        let ((evaluation, d_binary2, d_grid, d_bias), found) =
            evaluate_field_with_lanes(scene, binary2, &grid, &bias, lane.as_ref())?;
        let mut point =
            point_gradient(scene, &evaluation, parameters, d_binary2, &d_grid, bases, d_bias.as_ref(), found.as_ref())?;
        weigh_by_noise(scene, &evaluation, parameters, binary2, &grid, &mut point)?;
        return Ok(Gradient {
            evaluation,
            asnr: point.asnr,
            mean_mtf: point.mean_mtf,
            snr0: point.snr0,
            photoelectrons: point.photoelectrons,
        });
    }
    let evaluation = crate::evaluate(scene)?;
    let points = scene.fields().len();
    for p in parameters {
        if let Parameter::FieldPointAngle { point, .. } = *p
            && point >= points
        {
            return Err(Error::NotDifferentiable {
                parameter: p.describe(),
                reason: format!("fields[{point}]: the scene's [[fields]] list has {points} points (0-based)"),
            });
        }
    }
    // the weighted mean of the points' derivatives, with evaluate's relative weights
    let largest = scene.fields().iter().map(|f| f.1).fold(0.0, f64::max);
    let relative: Vec<f64> = scene.fields().iter().map(|f| f.1 / largest).collect();
    let total: f64 = relative.iter().sum();
    let zeros = vec![0.0; parameters.len()];
    let mut sum =
        PointGradient { asnr: zeros.clone(), mean_mtf: zeros.clone(), snr0: zeros.clone(), photoelectrons: zeros };
    for (j, (&(field, _), w)) in scene.fields().iter().zip(&relative).enumerate() {
        let single = scene.single_field(field);
        // a point's own field angles are this point's field angles; another point's do not
        // move it (derivative 0 here)
        let local: Vec<Option<Parameter>> = parameters
            .iter()
            .map(|p| match *p {
                Parameter::FieldPointAngle { point, axis } => (point == j).then_some(Parameter::FieldAngle(axis)),
                p => Some(p),
            })
            .collect();
        let kept: Vec<Parameter> = local.iter().flatten().copied().collect();
        let mut grid: Vec<optics::WavefrontDirection> = kept.iter().filter_map(|p| p.grid_direction()).collect();
        let bases = point_aperture_on_grid(&single, bases, field, &mut grid);
        let (e, d_binary2, d_grid, d_bias) = evaluate_field_differentiated(&single, binary2, &grid, &bias)?;
        let mut point = point_gradient(&single, &e, &kept, d_binary2, &d_grid, bases, d_bias.as_ref(), None)?;
        weigh_by_noise(&single, &e, &kept, binary2, &grid, &mut point)?;
        for (s, p) in [
            (&mut sum.asnr, &point.asnr),
            (&mut sum.mean_mtf, &point.mean_mtf),
            (&mut sum.snr0, &point.snr0),
            (&mut sum.photoelectrons, &point.photoelectrons),
        ] {
            let mut p = p.iter();
            for (s, l) in s.iter_mut().zip(&local) {
                if l.is_some()
                    && let Some(p) = p.next()
                {
                    *s += w * p / total;
                }
            }
        }
    }
    Ok(Gradient {
        evaluation,
        asnr: sum.asnr,
        mean_mtf: sum.mean_mtf,
        snr0: sum.snr0,
        photoelectrons: sum.photoelectrons,
    })
}

/// A `[[fields]]` point's lane bases: where the aperture's lanes ride the radial engine
/// ([`ExtraLanes`]) and the point is off axis, they ride its FFT pass instead, with the oblique
/// wave's ([`aperture_grid_directions`], appended to `grid`), as at a single `[field]` point off
/// axis: the field-of-view mean is the weighted mean of the points' values, so its gradient is the
/// weighted mean of each point's (docs/physics.md, "Gradients: the F-number and the focal length of
/// a phase lens off axis").
fn point_aperture_on_grid(
    scene: &Scene,
    bases: LaneBases,
    field: optics::Field,
    grid: &mut Vec<optics::WavefrontDirection>,
) -> LaneBases {
    match bases.aperture {
        Some(base) if radial_on_grid(scene, field) => {
            let directions = aperture_grid_directions(base, !field.is_on_axis());
            let aperture_on_grid = directions.len();
            grid.extend(directions);
            LaneBases { aperture_on_grid, ..bases }
        }
        _ => LaneBases { aperture_on_grid: 0, ..bases },
    }
}

/// The lane to ask of the value's own pass ([`evaluate_field_with_lanes`]): a line's wavelength
/// on a lens whose orders are full circles with a defocus alone — the order lane where the lens
/// gives each order's rates ([`optics::LensModel::order_wavelength_rates`]: the harmonic lens),
/// else `∂O/∂ln K` — or the F-number and focal length where their lanes are not the radial
/// engine's. `None` where none of these is asked.
fn defocus_lane(scene: &Scene, parameters: &[Parameter], bases: LaneBases) -> Option<DefocusLane> {
    let line = crate::evaluate::detected_spectrum(scene).line();
    if let Some(line) = line
        && bases.wavelength.is_none()
        && parameters.contains(&Parameter::SpectrumCenter)
    {
        return Some(DefocusLane { rates: order_lane_rates(scene, line.center()) });
    }
    let aperture = parameters.iter().any(|p| matches!(p, Parameter::FNumber | Parameter::FocalLength));
    (aperture && bases.aperture.is_none()).then_some(DefocusLane { rates: None })
}

/// Per order at the line's wavelength `c`, `[α_o, γ_o]` of the order lane
/// ([`optics::Polychromatic::mean_mtf_and_order_lane`]): `α_o = ∂ln w_o/∂c = W020_o′/W020_o − 1/c`
/// (0 where `W020_o = 0`: `w ∂H/∂w` is 0 there, `H` being even in `w`) and `γ_o = ∂τ_o/∂c`, for a
/// lens that gives each order's rates ([`optics::LensModel::order_wavelength_rates`]); `None`
/// otherwise.
fn order_lane_rates(scene: &Scene, c: f64) -> Option<Vec<[f64; 2]>> {
    let lens = scene.lens();
    let rates = lens.order_wavelength_rates(c, scene.field())?;
    let orders = lens.orders(c, scene.field());
    if orders.len() != rates.orders.len() {
        return None;
    }
    Some(
        orders
            .iter()
            .zip(&rates.orders)
            .map(|(o, [d_w020, d_tau])| {
                let w020 = o.wavefront.defocus_m;
                [if w020 == 0.0 { 0.0 } else { d_w020 / w020 - 1.0 / c }, *d_tau]
            })
            .collect(),
    )
}

struct PointGradient {
    asnr: Vec<f64>,
    mean_mtf: Vec<f64>,
    snr0: Vec<f64>,
    photoelectrons: Vec<f64>,
}

/// `∂G` from `∂M̄` where the Nyquist frequency does not move: the metric's `G` is the mean MTF
/// `M̄`, or the MTF's integral up to Nyquist, `ν_N M̄` (`options.form`).
fn d_g_from_mean_mtf(scene: &Scene, e: &Evaluation, d_mtf: f64) -> f64 {
    match scene.options().form {
        MetricForm::Mean => d_mtf,
        MetricForm::Integral => e.nyquist_cyc_per_mm * d_mtf,
    }
}

/// The derivatives at one field point whose evaluation is `e`; `d_binary2` the mean MTF's
/// Binary 2 derivatives computed with it, where they were; `d_grid` the wavefront derivatives on
/// the FFT path, one per wavefront parameter of `parameters` in their order.
///
/// `bases`: where the F-number and focal length ride the radial engine's lanes (a phase lens,
/// [`ExtraLanes`]), the first of their three lanes `[P, T, S]`; where a line's wavelength does,
/// the first of its lanes. `d_bias`: a library lens's bias lanes computed with the evaluation,
/// one per `LibraryBias` of `parameters` in their order, where the value's engine gave them.
// the point's evaluation and every lane its pass gave, each its own argument
#[allow(clippy::too_many_arguments)]
fn point_gradient(
    scene: &Scene,
    e: &Evaluation,
    parameters: &[Parameter],
    d_binary2: Option<Vec<f64>>,
    d_grid: &GridGradient,
    bases: LaneBases,
    d_bias: Option<&BiasLanes>,
    found: Option<&DefocusFound>,
) -> Result<PointGradient, Error> {
    let aperture_base = bases.aperture;
    let camera = scene.camera();
    let sensor = camera.sensor();
    let exposure = scene.exposure();
    let n = e.photoelectrons;
    let transmitted = e.transmitted_photoelectrons;
    // the budget exactly as evaluate forms it
    let background = match scene.options().glare {
        GlareMode::FirstOrder => 0.0,
        GlareMode::Included => (transmitted - n).max(0.0),
    };
    let budget = noise::budget(sensor, n, background, exposure)?;
    let not_smooth =
        |parameter: Parameter, reason: String| Error::NotDifferentiable { parameter: parameter.describe(), reason };
    let partials: Option<SnrPartials> = budget.snr_partials();
    // G = ASNR / SNR0: the mean MTF (or its mean over the noise spectrum, or the MTF integral)
    let g = e.asnr / e.snr0;
    let mut out = PointGradient {
        asnr: Vec::with_capacity(parameters.len()),
        mean_mtf: Vec::with_capacity(parameters.len()),
        snr0: Vec::with_capacity(parameters.len()),
        photoelectrons: Vec::with_capacity(parameters.len()),
    };
    // the stray light B = max(N_T − N, 0) with glare included: its derivative where it is > 0
    let stray = matches!(scene.options().glare, GlareMode::Included) && background > 0.0;
    // the radial engine's lanes, or the FFT path's derivatives (`d_grid`), whichever the
    // evaluation computed
    let on_grid = matches!(d_grid, GridGradient::Computed(_));
    let on_lanes = |p: &&Parameter| {
        p.lane().is_some()
            || (aperture_base.is_some() && matches!(p, Parameter::FNumber | Parameter::FocalLength))
            || (bases.wavelength.is_some() && **p == Parameter::SpectrumCenter)
    };
    let binary2 = match parameters.iter().find(on_lanes) {
        Some(&p) if !on_grid => Some(binary2_mean_mtf(p, d_binary2)?),
        _ => None,
    };
    // each parameter's place among the FFT path's directions, and among the bias lanes
    let mut grid_place = 0;
    let mut bias_place = 0;
    // a line: its wavelength moves N and each order's OTF at it, its equivalent width N alone
    let line = crate::evaluate::detected_spectrum(scene).line();
    let spectral = match parameters.iter().find(|p| matches!(p, Parameter::SpectrumCenter | Parameter::SpectrumRange)) {
        Some(&p) if line.is_none() => Some(spectral_partials(scene, e, p)?),
        _ => None,
    };
    // under a noise spectrum the band's lanes again with each frequency's weight divided by n(ν)
    let spectral_over_noise = match (camera.noise_spectrum(), &spectral) {
        (Some(shape), Some(_)) => {
            let p = parameters.iter().find(|p| matches!(p, Parameter::SpectrumCenter | Parameter::SpectrumRange));
            Some(spectral_partials_over(scene, e, *p.expect("a spectral key"), Some(shape))?)
        }
        _ => None,
    };
    let line_center = match line {
        Some(_) if parameters.contains(&Parameter::SpectrumCenter) => {
            Some(line_center_partials(scene, e, binary2.as_deref(), bases.wavelength, found)?)
        }
        _ => None,
    };
    // the Seidel terms at zero on a rotationally symmetric OTF: spherical aberration's and field
    // curvature's lanes on the overlap engine (astigmatism's from field curvature's)
    let seidel_zero = match parameters.iter().find(|p| {
        matches!(p, Parameter::Seidel(t) if *t != optics::SeidelTerm::Coma) && *d_grid == GridGradient::Symmetric
    }) {
        Some(_) => seidel_at_zero(scene)?,
        None => None,
    };
    // both band edges' lanes from one pass, made for the first edge (or aperture key) asked
    let edge_pass = achromat::EdgePass::default();
    let aperture = match parameters.iter().find(|p| matches!(p, Parameter::FNumber | Parameter::FocalLength)) {
        Some(&p) if aperture_base.is_none() => 'found: {
            // a lens with a design band: the lanes on the band edges' pass
            if let Some(found) =
                achromat::aperture_on_edge_pass(scene, e, p, &edge_pass, found.is_some_and(|f| !f.order_lane))?
            {
                break 'found Some(found);
            }
            // the defocus lane the value's pass gave on the overlap engine, after the
            // parameters' own directions (`gradient`)
            let lane = match d_grid {
                GridGradient::Computed(all)
                    if all.len() == parameters.iter().filter(|p| p.grid_direction().is_some()).count() + 1 =>
                {
                    all.last().copied()
                }
                _ => None,
            };
            Some(aperture_partials(scene, e, p, found.filter(|f| !f.order_lane), lane)?)
        }
        Some(&p) => {
            let on_grid = match d_grid {
                GridGradient::Computed(all) if bases.aperture_on_grid > 0 => {
                    all.len().checked_sub(bases.aperture_on_grid).map(|at| &all[at..])
                }
                _ => None,
            };
            Some(aperture_lane_partials(scene, e, p, binary2.as_deref(), aperture_base, on_grid)?)
        }
        None => None,
    };
    for &p in parameters {
        let Some(partials) = partials else {
            return Err(not_smooth(
                p,
                if budget.saturated {
                    "the pixel saturates: the charges are clipped at the well, where the SNR has a kink".to_owned()
                } else {
                    "there is no signal".to_owned()
                },
            ));
        };
        // ∂N, ∂B, ∂(dark charge), ∂σ_r², ∂(σ_q²/K²), and ∂G
        let (d_n, d_b, d_dark, d_read, d_quant, d_g, d_mtf) = match p {
            Parameter::SignalScale => (n, background, 0.0, 0.0, 0.0, 0.0, 0.0),
            Parameter::Exposure => (n, background, budget.dark_e, 0.0, 0.0, 0.0, 0.0),
            Parameter::Efficiency => (n, if stray { -n } else { 0.0 }, 0.0, 0.0, 0.0, 0.0, 0.0),
            Parameter::Transmission => (0.0, if stray { transmitted } else { 0.0 }, 0.0, 0.0, 0.0, 0.0, 0.0),
            Parameter::ReadNoise => (0.0, 0.0, 0.0, 2.0 * sensor.read_noise_e(), 0.0, 0.0, 0.0),
            Parameter::DarkCurrent => (0.0, 0.0, exposure, 0.0, 0.0, 0.0, 0.0),
            Parameter::Gain => {
                let Some(k) = sensor.gain_dn_per_e() else {
                    return Err(not_smooth(p, "the camera has no ADC (camera.gain_dn_per_e not given)".to_owned()));
                };
                (0.0, 0.0, 0.0, 0.0, -2.0 * budget.quantization_variance_e2 / k, 0.0, 0.0)
            }
            Parameter::PixelPitch => {
                // ν_N = 1/(2p): ∂ν_N/∂ln p = −ν_N. Leibniz: ∂M̄/∂ν_N = (MTF(ν_N) − M̄)/ν_N, so
                // ∂M̄/∂ln p = M̄ − MTF(ν_N); the integral I = M̄ ν_N: ∂I/∂ln p = −ν_N MTF(ν_N).
                // With the pixel MTF, in x = ν/ν_N its sinc(πx/2) stays and the lens's OTF at
                // x ν_N moves: by parts ∂M̄/∂ln p = M̄ − P(ν_N)|O(ν_N)| + P_ν (MTF(ν_N) the
                // system's, P included), ∂I/∂ln p = ν_N (P_ν − P(ν_N)|O(ν_N)|)
                let edge = mtf_at(scene, &[e.nyquist_cyc_per_mm], &[])?.mtf[0];
                let slope = pixel_slope(scene, p)?;
                let d_mtf = e.mean_mtf - edge + slope;
                // under a noise spectrum n(ν), fixed in cycles/mm (the pitch moves the upper
                // limit only, and n is continuous there): G = (1/ν_N) ∫ MTF/n dν, so the same
                // Leibniz rule with MTF(ν_N)/n(ν_N) at the limit (docs/physics.md, "Gradients
                // under a noise spectrum"); with the pixel MTF its sinc's term P̃_ν weighted by 1/n
                let d_g = match (camera.noise_spectrum(), scene.options().form) {
                    (None, MetricForm::Mean) => d_mtf,
                    (None, MetricForm::Integral) => e.nyquist_cyc_per_mm * (slope - edge),
                    (Some(shape), form) => {
                        let edge = edge / shape.value(e.nyquist_cyc_per_mm * 1e3);
                        let slope = noise_weight::pixel_slope_over_noise(scene, e, p)?;
                        match form {
                            MetricForm::Mean => e.asnr_mean / e.snr0 - edge + slope,
                            MetricForm::Integral => e.nyquist_cyc_per_mm * (slope - edge),
                        }
                    }
                };
                (2.0 * n, 2.0 * background, 0.0, 0.0, 0.0, d_g, d_mtf)
            }
            Parameter::PsfPitch => psf_pitch_partials(scene, e, p)?,
            Parameter::Binary2(_)
            | Parameter::PhaseSpline(_)
            | Parameter::Zernike(_)
            | Parameter::ZernikeNoll(_)
            | Parameter::Seidel(_)
                if on_grid =>
            {
                let GridGradient::Computed(all) = d_grid else { unreachable!("on_grid") };
                let d_mtf = all[grid_place];
                grid_place += 1;
                let d_g = d_g_from_mean_mtf(scene, e, d_mtf);
                (0.0, 0.0, 0.0, 0.0, 0.0, d_g, d_mtf)
            }
            Parameter::Seidel(t) => {
                // every Seidel term zero on axis: the 1-D engines, rotationally symmetric; coma
                // at ±c is one pupil turned by π, whose mean over azimuth is the same
                if t == optics::SeidelTerm::Coma && *d_grid == GridGradient::Symmetric {
                    (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
                } else if let Some([spherical, curvature]) = seidel_zero {
                    // astigmatism W222 x² = W222 ρ²/2 + W222 ρ² cos 2φ/2: the defocus part half
                    // field curvature's, the cos 2φ part 0 by symmetry (c and −c are one pupil
                    // turned by π/2, whose mean over azimuth is the same)
                    let d_mtf = match t {
                        optics::SeidelTerm::Spherical => spherical,
                        optics::SeidelTerm::FieldCurvature => curvature,
                        _ => 0.5 * curvature,
                    };
                    let d_g = d_g_from_mean_mtf(scene, e, d_mtf);
                    (0.0, 0.0, 0.0, 0.0, 0.0, d_g, d_mtf)
                } else if let Some(d_mtf) = seidel_at_zero_off_axis(scene, e, t)? {
                    let d_g = d_g_from_mean_mtf(scene, e, d_mtf);
                    (0.0, 0.0, 0.0, 0.0, 0.0, d_g, d_mtf)
                } else {
                    return Err(not_smooth(
                        p,
                        format!(
                            "{}: the Seidel gradient is computed on the overlap engine, for a lens whose every order is \
                             the full circle with Seidel terms; this scene's OTF is {}",
                            t.key(),
                            match d_grid {
                                GridGradient::Symmetric =>
                                    "rotationally symmetric on the 1-D engines (every Seidel term zero), and its pupil is not \
                                     one the overlap engine takes at zero Seidel terms (an iris, \
                                     options.overlap = false or options.pupil_samples)",
                                _ =>
                                    "not on the overlap engine nor on the FFT path through an iris or under a line (a phase \
                                     profile, a table, a wavefront too strong for the overlap rules, or other wavefront keys \
                                     asked with it)",
                            }
                        ),
                    ));
                }
            }
            Parameter::ZernikeNoll(j) => {
                let (n_radial, m) = optics::fft::noll_to_nm(j);
                if m == 0 || *d_grid != GridGradient::Symmetric {
                    return Err(not_smooth(
                        p,
                        format!(
                            "Noll {j} (n = {n_radial}, m = {m}): the Zernike gradient is computed on the FFT path for a lens whose \
                             every order is a radially symmetric pupil carrying the terms (with m = 0 terms on the radial \
                             engine for lens.model = \"phase\" only); this scene's OTF is {}",
                            match d_grid {
                                GridGradient::Symmetric =>
                                    "rotationally symmetric, on the radial engine, which follows the m = 0 terms of a phase lens only",
                                _ =>
                                    "not on those grids (an iris, zones, a map, a table, a line spectrum's grids, or an order of another kind)",
                            }
                        ),
                    ));
                }
                // every m ≠ 0 term is zero and the pupil radially symmetric: c and −c are one
                // pupil turned by π/|m|, whose mean over azimuth is the same (an even function of c)
                (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
            }
            Parameter::Binary2(i) | Parameter::PhaseSpline(i) | Parameter::Zernike(i) => {
                let all = binary2.as_deref().unwrap_or(&[]);
                let Some(&d_mtf) = all.get(i) else {
                    return Err(not_smooth(
                        p,
                        format!(
                            "the lens has {} wavefront directions (Binary 2 coefficients, spline knots, m = 0 Zernike terms; 0-based)",
                            all.len()
                        ),
                    ));
                };
                let d_g = d_g_from_mean_mtf(scene, e, d_mtf);
                (0.0, 0.0, 0.0, 0.0, 0.0, d_g, d_mtf)
            }
            Parameter::FNumber | Parameter::FocalLength => {
                let (d_f_number, d_focal_length) = aperture.expect("computed above for an aperture parameter");
                let d_mtf = if p == Parameter::FNumber { d_f_number } else { d_focal_length };
                let d_g = match camera.noise_spectrum() {
                    None => d_g_from_mean_mtf(scene, e, d_mtf),
                    Some(_) => {
                        let (f, f0) =
                            noise_weight::aperture_over_noise(scene, e, p, bases.aperture, bases.aperture_on_grid)?;
                        d_g_from_mean_mtf(scene, e, if p == Parameter::FNumber { f } else { f0 })
                    }
                };
                if p == Parameter::FNumber {
                    // N and N_T ∝ NA² = 1/(4F#²) (SI eq. S7–S8, S14): ∂ln/∂ln F# = −2 for both,
                    // so the stray light N_T − N too
                    (-2.0 * n, -2.0 * background, 0.0, 0.0, 0.0, d_g, d_mtf)
                } else {
                    (0.0, 0.0, 0.0, 0.0, 0.0, d_g, d_mtf)
                }
            }
            Parameter::FieldPointAngle { point, axis } => {
                return Err(not_smooth(
                    p,
                    format!(
                        "fields[{point}].{}: the scene has a single field point, not a [[fields]] list",
                        if axis == 0 { "x_deg" } else { "y_deg" }
                    ),
                ));
            }
            Parameter::FieldAngle(axis) => {
                let d_mtf = match d_grid {
                    // orders the same at every field point in its frame (a PSF stack): the mean
                    // MTF does not depend on the field angles (`LensModel::turns_with_field`)
                    _ if scene.lens().turns_with_field() => {
                        if matches!(d_grid, GridGradient::Computed(_)) {
                            grid_place += 1;
                        }
                        0.0
                    }
                    // on axis, a rotationally symmetric pupil: M̄ is even in the angle (0)
                    _ => match d_grid.next_lane(&mut grid_place) {
                        Some(d) => d,
                        None => {
                            return Err(not_smooth(
                                p,
                                format!(
                                    "{key}: the field angle's OTF lane is computed on the exact 1-D engine (off axis without \
                                 Seidel terms) and the overlap engine (Seidel or Zernike terms) as the \
                                 lateral colour's shifts, on the FFT path as the lateral colour's shifts of sampled pupils (an annulus, \
                                 an iris with Seidel terms, Zernike terms) and the oblique wave's path of a radial pupil seen off axis (a \
                                 phase or library lens), and is 0 by symmetry on axis for a rotationally symmetric pupil; \
                                 this scene's OTF is on another engine or pupil (an iris on the exact 1-D engine with \
                                 another aberration, zones, a map or a table; a line spectrum's grids)",
                                    key = field_key(axis)
                                ),
                            ));
                        }
                    },
                };
                let d_ln_ri = scene
                    .relative_illumination()
                    .field_log_derivative(scene.field(), axis)
                    .map_err(|why| not_smooth(p, format!("{}: {why}", field_key(axis))))?;
                let d_g = d_g_from_mean_mtf(scene, e, d_mtf);
                // RI scales N and N_T alike (docs/physics.md, "Relative illumination"), so the
                // stray light N_T − N in proportion
                (n * d_ln_ri, background * d_ln_ri, 0.0, 0.0, 0.0, d_g, d_mtf)
            }
            Parameter::IrisDecentre(axis) => {
                // the iris centred on a rotationally symmetric OTF: d and −d are one pupil
                // mirrored, whose mean over azimuth is the same (M̄ even in d: the lane 0)
                let d_mtf = match d_grid.next_lane(&mut grid_place) {
                    Some(d) => d,
                    None => {
                        return Err(not_smooth(
                            p,
                            format!(
                                "lens.iris_decentre_{}: the decentre's lane is computed on the exact 1-D engine, for a \
                                 circular iris on orders whose only aberration is defocus (the centred circle with the \
                                 tilt 2 W020 d), on the FFT path for an iris with Seidel terms, an annulus or a sector \
                                 (the wavefront's slope at each pixel), and is 0 by symmetry where the OTF is \
                                 rotationally symmetric; this scene's pupil is on another engine (Zernike terms, a \
                                 line spectrum's grids, or other wavefront keys asked with it)",
                                if axis == 0 { "x" } else { "y" }
                            ),
                        ));
                    }
                };
                let d_g = d_g_from_mean_mtf(scene, e, d_mtf);
                // the iris keeps its area (the full-size circle moved): N and N_T do not move
                (0.0, 0.0, 0.0, 0.0, 0.0, d_g, d_mtf)
            }
            Parameter::Obscuration => {
                let GridGradient::Computed(all) = d_grid else {
                    return Err(not_smooth(
                        p,
                        "lens.obscuration: the inner edge's motion is computed on the FFT path (a band's \
                        grids or a line's), for orders through the annulus (or annular sector) with its \
                        wavefront, asked with no wavefront key but Seidel and Zernike terms; this scene's \
                        OTF is on another engine or its grids give no lane"
                            .to_owned(),
                    ));
                };
                let d_mtf = all[grid_place];
                grid_place += 1;
                let d_g = d_g_from_mean_mtf(scene, e, d_mtf);
                // N and N_T move with the area fraction: the key's chain on Efficiency and
                // Transmission (`Parameter::Obscuration`)
                (0.0, 0.0, 0.0, 0.0, 0.0, d_g, d_mtf)
            }
            Parameter::MapPitch => {
                if camera.noise_spectrum().is_some() {
                    return Err(not_smooth(
                        p,
                        "lens.phase_map_pitch_um: computed with a white noise spectrum only (its lane under \
                         camera.noise_spectrum is not checked yet)"
                            .to_owned(),
                    ));
                }
                let Some(d_mtf) = d_grid.next_lane(&mut grid_place) else {
                    return Err(not_smooth(
                        p,
                        "lens.phase_map_pitch_um: the cells' motion is computed on the FFT path of a band, on axis, \
                         asked with no wavefront key; this scene is not that (off axis, or a line spectrum's grids)"
                            .to_owned(),
                    ));
                };
                let d_g = d_g_from_mean_mtf(scene, e, d_mtf);
                // the aperture and the efficiencies do not move with the cells: N and N_T stay
                (0.0, 0.0, 0.0, 0.0, 0.0, d_g, d_mtf)
            }
            Parameter::DesignWavelength => {
                // a design band's lens: on the band edges' pass where it gives λ0's lane too
                let (d_ln_n, d_mtf) = match achromat::design_wavelength_on_edge_pass(scene, e, &edge_pass) {
                    Some(found) => found,
                    None => design_wavelength_partials(scene, e, p)?,
                };
                let d_weighted = match camera.noise_spectrum() {
                    Some(shape) => design_wavelength_over_noise(scene, e, p, shape)?,
                    None => d_mtf,
                };
                let d_g = d_g_from_mean_mtf(scene, e, d_weighted);
                // N ∝ ∫ ρ Σ τ_o; T (so N_T) does not depend on λ0: B = N_T − N moves by −∂N
                let d_n = n * d_ln_n;
                (d_n, if stray { -d_n } else { 0.0 }, 0.0, 0.0, 0.0, d_g, d_mtf)
            }
            Parameter::BandEdge(edge) => {
                let (d_ln_n, d_mtf) = achromat::band_edge_partials(scene, e, p, edge, None, &edge_pass)?;
                let d_weighted = match camera.noise_spectrum() {
                    Some(shape) => achromat::band_edge_partials(scene, e, p, edge, Some(shape), &edge_pass)?.1,
                    None => d_mtf,
                };
                let d_g = d_g_from_mean_mtf(scene, e, d_weighted);
                // N ∝ ∫ ρ Σ τ_o over the band; T (so N_T) does not move: B = N_T − N by −∂N
                let d_n = n * d_ln_n;
                (d_n, if stray { -d_n } else { 0.0 }, 0.0, 0.0, 0.0, d_g, d_mtf)
            }
            Parameter::SpectrumCenter | Parameter::SpectrumRange if line.is_some() => {
                // N ∝ (the line's weight) Σ τ_o(c) and N_T ∝ (the weight) T(c): the stray light
                // B = N_T − N moves by N_T ∂ln N_T − N ∂ln N
                let (d_ln_n, d_ln_t, d_mtf) = match (p, line) {
                    (Parameter::SpectrumRange, Some(l)) => (1.0 / l.width(), 1.0 / l.width(), 0.0),
                    _ => line_center.expect("computed above for a line's wavelength"),
                };
                let d_weighted = match camera.noise_spectrum() {
                    Some(_) if p == Parameter::SpectrumCenter => {
                        noise_weight::line_center_over_noise(scene, e, bases.wavelength)?
                    }
                    _ => d_mtf,
                };
                let d_g = d_g_from_mean_mtf(scene, e, d_weighted);
                let d_b = if stray { transmitted * d_ln_t - n * d_ln_n } else { 0.0 };
                (n * d_ln_n, d_b, 0.0, 0.0, 0.0, d_g, d_mtf)
            }
            Parameter::Temperature => {
                let (d_ln_n, d_mtf) = temperature_partials(scene, e, p)?;
                // a line: the OTF is the lens's at one wavelength, whatever the weight; N and
                // N_T both ∝ B(c, T). Over a band N_T = ∫ ρ T moves by its own average of g
                let d_b = match line {
                    Some(_) => background * d_ln_n,
                    // B = N_T − N: N_T's own average of g over ρ T ([`transmitted_band_log_derivative`])
                    None if stray => transmitted * transmitted_band_log_derivative(scene, p)? - n * d_ln_n,
                    None => 0.0,
                };
                let d_weighted = match camera.noise_spectrum() {
                    Some(shape) if line.is_none() => temperature_partials_over(scene, e, p, Some(shape))?.1,
                    _ => d_mtf,
                };
                let d_g = d_g_from_mean_mtf(scene, e, d_weighted);
                (n * d_ln_n, d_b, 0.0, 0.0, 0.0, d_g, d_mtf)
            }
            Parameter::SpectrumCenter | Parameter::SpectrumRange => {
                let s = spectral.as_ref().expect("computed above for a spectral parameter");
                let (d_ln_n, d_mtf) = if p == Parameter::SpectrumCenter { s.center } else { s.range };
                let d_weighted = match &spectral_over_noise {
                    Some(w) if p == Parameter::SpectrumCenter => w.center.1,
                    Some(w) => w.range.1,
                    None => d_mtf,
                };
                let d_g = d_g_from_mean_mtf(scene, e, d_weighted);
                // N = (constants) ∫ ρ τ1 dλ and N_T = (the same constants) ∫ ρ T dλ (SI eq. S8,
                // S14): the stray light B = N_T − N moves by N_T ∂ln N_T − N ∂ln N, N_T's
                // derivative its own average over ρ T ([`transmitted_band_log_derivative`])
                let d_b =
                    if stray { transmitted * transmitted_band_log_derivative(scene, p)? - n * d_ln_n } else { 0.0 };
                (n * d_ln_n, d_b, 0.0, 0.0, 0.0, d_g, d_mtf)
            }
            Parameter::LibraryBias(index) => {
                let on_value_rule = d_bias.map(|d| BiasPartials {
                    ln_photoelectrons: d.ln_photoelectrons[bias_place],
                    ln_transmitted: d.ln_transmitted[bias_place],
                    mean_mtf: d.mean_mtf[bias_place],
                });
                bias_place += 1;
                let bias = match on_value_rule {
                    Some(b) => b,
                    _ => library_bias_partials(scene, e, p, index)?,
                };
                let d_weighted = match camera.noise_spectrum() {
                    Some(shape) => library_bias_partials_over(scene, e, p, index, Some(shape))?.mean_mtf,
                    None => bias.mean_mtf,
                };
                let d_g = d_g_from_mean_mtf(scene, e, d_weighted);
                // N ∝ ∫ρ τ1 dλ and N_T ∝ ∫ρ T dλ (SI eq. S8, S14); the stray light B = N_T − N
                let d_n = n * bias.ln_photoelectrons;
                let d_b = if stray { transmitted * bias.ln_transmitted - d_n } else { 0.0 };
                (d_n, d_b, 0.0, 0.0, 0.0, d_g, bias.mean_mtf)
            }
        };
        let d_snr0 = partials.signal * d_n + partials.variance * (d_b + d_dark + d_read + d_quant);
        out.photoelectrons.push(d_n);
        out.snr0.push(d_snr0);
        out.mean_mtf.push(d_mtf);
        out.asnr.push(d_snr0 * g + e.snr0 * d_g);
    }
    Ok(out)
}

/// Under a non-white noise spectrum `n` (`camera.noise_spectrum`), the ASNR's derivatives
/// along the wavefront keys (every parameter with a [`Parameter::grid_direction`]) from the
/// noise-weighted mean `G = (1/ν_N) ∫ MTF/n dν` the ASNR takes, in place of the white mean's in
/// `point` (docs/physics.md, "Gradients under a noise spectrum"): `n` does not move with the
/// lens, so `∂G = (1/ν_N) ∫ ∂MTF/n dν`, the white lanes with each frequency's weight divided by
/// `n(ν)`, on the value's own noise-weighted pass ([`crate::evaluate::noise_weighted_lanes`]).
/// `∂SNR0` and `∂M̄` stay `point`'s. A key whose white derivative is 0 by the OTF's symmetry
/// (an `m ≠ 0` Zernike term, coma, a field angle or an iris's decentre on a rotationally
/// symmetric OTF) is 0 under the noise weight too (`n` depends on `|ν|` alone); a key with no
/// weighted lane here is refused naming it. Nothing to do with white noise.
fn weigh_by_noise(
    scene: &Scene,
    e: &Evaluation,
    parameters: &[Parameter],
    binary2: bool,
    grid: &[optics::WavefrontDirection],
    point: &mut PointGradient,
) -> Result<(), Error> {
    if scene.camera().noise_spectrum().is_none() || !parameters.iter().any(|p| p.grid_direction().is_some()) {
        return Ok(());
    }
    let lanes = crate::evaluate::noise_weighted_lanes(scene, binary2, grid)?;
    let g = e.asnr / e.snr0;
    let mut place = 0;
    for (k, &p) in parameters.iter().enumerate() {
        if p.grid_direction().is_none() {
            continue;
        }
        let on_grid = match &lanes.grid {
            GridGradient::Computed(all) => all.get(place).copied(),
            _ => None,
        };
        place += 1;
        let symmetric = lanes.grid == GridGradient::Symmetric;
        let weighted = match p {
            _ if on_grid.is_some() => on_grid,
            Parameter::Binary2(i) | Parameter::PhaseSpline(i) | Parameter::Zernike(i) => {
                lanes.binary2.as_ref().and_then(|all| all.get(i)).copied()
            }
            Parameter::FieldAngle(_) if scene.lens().turns_with_field() => Some(0.0),
            Parameter::ZernikeNoll(_)
            | Parameter::Seidel(optics::SeidelTerm::Coma)
            | Parameter::FieldAngle(_)
            | Parameter::IrisDecentre(_)
                if symmetric =>
            {
                Some(0.0)
            }
            // every Seidel term zero: the overlap engine run again at zero, weighted
            Parameter::Seidel(t) => match scene.camera().noise_spectrum() {
                Some(shape) => noise_weight::seidel_at_zero_over_noise(scene, e, t, shape)?,
                None => None,
            },
            _ => None,
        };
        let Some(d_weighted) = weighted else {
            return Err(Error::NotDifferentiable { parameter: p.describe(), reason: noise_refusal(p) });
        };
        point.asnr[k] = point.snr0[k] * g + e.snr0 * d_g_from_mean_mtf(scene, e, d_weighted);
    }
    Ok(())
}

/// Why [`weigh_by_noise`] has no weighted lane for `p` here, naming its key.
fn noise_refusal(p: Parameter) -> String {
    let passes = "with camera.noise_spectrum the wavefront and field keys' lanes are taken on the value's \
                  noise-weighted pass of the radial engine (Binary 2 coefficients, spline knots, m = 0 Zernike \
                  terms on axis), the exact 1-D engine (a circular iris's decentre, the field angles' lateral \
                  colour), the overlap engine (Seidel and Zernike terms, at zero too) and the FFT path (a band or a line), \
                  and are 0 where the OTF's symmetry makes them so";
    let (key, here) = match p {
        Parameter::IrisDecentre(a) => (
            format!("lens.iris_decentre_{}", if a == 0 { "x" } else { "y" }),
            "this scene's pupil is on none of them (a line spectrum's grids, or the iris with Seidel or Zernike \
             terms on a rule that carries no decentre lane)",
        ),
        Parameter::Seidel(t) => (
            t.key().to_owned(),
            "this scene's pupil is on none of them (every term zero through an iris, which the overlap engine does \
             not take at zero; options.overlap = false or options.pupil_samples; a line spectrum's grids)",
        ),
        Parameter::FieldAngle(a) => (
            field_key(a).to_owned(),
            "this scene's OTF is on none of them (a table, zones or a map; a line spectrum's grids)",
        ),
        Parameter::ZernikeNoll(j) => (
            format!("lens.zernike_noll_rms_um[{}]", j.saturating_sub(1)),
            "this scene's pupil is on none of them (a line spectrum's grids, or an order of another kind)",
        ),
        Parameter::Obscuration => (
            "lens.obscuration".to_owned(),
            "its edge's lane rides on the FFT path of a band or a line, asked with no wavefront key but Seidel and \
             Zernike terms; this scene is not that",
        ),
        _ => (p.describe().to_owned(), "this key's lane is on another rule here"),
    };
    format!("{key}: {passes}; {here}")
}

/// One parameter's `(∂N, ∂B, ∂(dark charge), ∂σ_r², ∂(σ_q²/K²), ∂G, ∂M̄)` at a field point.
type PointPartials = (f64, f64, f64, f64, f64, f64, f64);

/// [`PointPartials`] per relative change of a PSF stack's sample pitch
/// ([`Parameter::PsfPitch`]): the OTF is `O(ν p/p0)` at every wavelength, so on `[0, ν_N]` the
/// change of variables `u = νp/p0` gives `M̄(p) = (p0/p)/ν_N ∫_0^{ν_N p/p0} MTF(u) du` and
/// `∂M̄/∂ln p = MTF(ν_N) − M̄`; N and the noise do not move. Under a noise spectrum the weighted
/// mean's change of scale ([`noise_weight::frequency_scale_over_noise`]: its `n′` term over the
/// value's directions).
fn psf_pitch_partials(scene: &Scene, e: &Evaluation, p: Parameter) -> Result<PointPartials, Error> {
    // with the pixel MTF P (its sinc does not scale with the stack's pitch) the OTF's change of
    // scale is ν ∂_ν O, by parts P(ν_N)|O(ν_N)| − M̄ − P_ν (MTF(ν_N) the system's, P included)
    let edge = mtf_at(scene, &[e.nyquist_cyc_per_mm], &[])?.mtf[0];
    let d_mtf = edge - e.mean_mtf - pixel_slope(scene, p)?;
    // under a noise spectrum n (fixed in cycles/mm) the same change of scale of the weighted
    // mean G: by parts P(ν_N)|O(ν_N)|/n(ν_N) − G − (1/ν_N) ∫ P |O| (νP′/P − νn′/n)/n dν, averaged
    // over the value's directions as G is
    let d_weighted = match scene.camera().noise_spectrum() {
        Some(_) => noise_weight::frequency_scale_over_noise(scene, e, p, edge)?,
        None => d_mtf,
    };
    Ok((0.0, 0.0, 0.0, 0.0, 0.0, d_g_from_mean_mtf(scene, e, d_weighted), d_mtf))
}

/// The pixel MTF's term of the integration by parts in ν, `P_ν = (1/ν_N) ∫ ν P′(ν) |O(ν)| dν`
/// (`P` the pixel MTF, `νP′/P = x cot x − 1`, `x = πpν`; docs/physics.md, "Gradients: the
/// pixel pitch with the pixel MTF"), on the value's own engine and frequency rule
/// ([`optics::Polychromatic::mean_mtf_and_pixel_slope`]: `|O|` recorded at each frequency the
/// rule reads, integrated with its accepted weights), averaged over the value's azimuths as
/// the mean MTF is (on the FFT path, its fixed rule on the value's sampling levels). 0 without
/// the pixel MTF. Refused, naming `p`, where the engine gives no modulus to record.
fn pixel_slope(scene: &Scene, p: Parameter) -> Result<f64, Error> {
    if !scene.camera().pixel_mtf() {
        return Ok(0.0);
    }
    let field = scene.field();
    let along_field = field.y_rad.atan2(field.x_rad);
    let detected = crate::evaluate::detected_spectrum(scene);
    on_value_engine(scene, &detected, scene.options().settings(), |poly| {
        poly.mean_mtf_and_pixel_slope(along_field).map(|found| found.1)
    })
    .ok_or_else(|| Error::NotDifferentiable {
        parameter: p.describe(),
        reason: "with camera.pixel_mtf = true the pixel's sinc term of the integration by parts is taken on the \
                 value's frequency rule, |O| recorded at each frequency read; this scene's engine gives no |O| \
                 along an azimuth to record (set camera.pixel_mtf = false)"
            .to_owned(),
    })
}

/// The scene key of the field angle `axis` (0: x, 1: y).
fn field_key(axis: usize) -> &'static str {
    if axis == 0 { "field.x_deg" } else { "field.y_deg" }
}

/// Where the extra lanes of [`ExtraLanes`] start among the lens's wavefront directions: the
/// aperture's `[P, T, S]` and the wavelength's terms, where they were asked.
#[derive(Clone, Copy, Debug, Default)]
struct LaneBases {
    aperture: Option<usize>,
    wavelength: Option<usize>,
    /// the aperture's lanes asked of the FFT path (a single field point off axis, or on axis a
    /// pupil without rotational symmetry): how many directions
    /// ([`aperture_grid_directions`]) follow the parameters' own, 0 where they ride the radial
    /// engine
    aperture_on_grid: usize,
}

/// The FFT path's directions of the F-number's and the focal length's gradient of a phase lens
/// off axis (`oblique`) or on axis with Zernike terms of `m ≠ 0` or Seidel terms, the aperture's
/// lanes starting at `base` among the wrapped lens's wavefront directions: `P`, `T`, `S`
/// ([`optics::LensModel::aperture_directions`]) and, off axis, the oblique wave's path per
/// `ln R` and per `ln` of the whole scale (docs/physics.md, "Gradients: the F-number and the
/// focal length of a phase lens off axis").
pub(super) fn aperture_grid_directions(base: usize, oblique: bool) -> Vec<optics::WavefrontDirection> {
    use optics::WavefrontDirection::{Lane, ObliqueScale};
    let mut out = vec![Lane(base), Lane(base + 1), Lane(base + 2)];
    if oblique {
        out.extend([ObliqueScale(0), ObliqueScale(1)]);
    }
    out
}

/// Whether the value of `scene` at `field` takes the FFT path for a lens whose orders are
/// radial pupils (a phase lens): off axis (the oblique wave's path), or on axis where an order's
/// pupil is not rotationally symmetric (Zernike terms of `m ≠ 0`) or carries Seidel terms
/// beyond defocus. Under a band only: a line's grids do not carry the aperture's lanes.
fn radial_on_grid(scene: &Scene, field: optics::Field) -> bool {
    if !field.is_on_axis() {
        return true;
    }
    if crate::evaluate::detected_spectrum(scene).as_line().is_some() {
        return false;
    }
    let lens = scene.lens();
    let lambda = lens.design_wavelength().unwrap_or(550e-9);
    lens.orders(lambda, field).iter().any(|o| match &o.pupil {
        optics::Pupil::Radial(p) => !(p.is_symmetric() && o.wavefront.is_defocus_only()),
        _ => false,
    })
}

/// A lens whose wavefront directions ([`optics::LensModel::binary2_directions`]) are its own
/// followed by its aperture directions `[P, T, S]` per order
/// ([`optics::LensModel::aperture_directions`]) and its wavelength directions
/// ([`optics::LensModel::wavelength_directions`]), each where asked, so that one pass of the
/// radial engine carries the F-number's, the focal length's and a line's wavelength's lanes
/// beside the value (and any Binary 2, spline and Zernike lanes asked with them). Everything
/// else is the lens's own.
#[derive(Debug)]
struct ExtraLanes {
    inner: std::sync::Arc<dyn optics::LensModel>,
    aperture: bool,
    wavelength: bool,
}

impl ExtraLanes {
    /// The scene with its lens so wrapped and where the extra lanes start, where the lens gives
    /// aperture directions (`aperture`: the F-number or focal length asked) or wavelength
    /// directions (`wavelength`: a line's wavelength asked, the scene under a line); `None`
    /// where it gives neither (the families whose F-number gradient is [`aperture_partials`]',
    /// whose line's wavelength is [`line_center_partials`]'). Off axis at a single field point
    /// the aperture's lanes ride on the FFT path with the oblique wave's
    /// ([`aperture_grid_directions`]); over a `[[fields]]` list each point off axis so on its own
    /// pass ([`point_aperture_on_grid`]); the wavelength's where the lens says why not.
    fn of(scene: &Scene, aperture: Option<Parameter>, wavelength: bool) -> Result<Option<(Scene, LaneBases)>, Error> {
        let lens = scene.lens();
        let lambda = lens.design_wavelength().unwrap_or(550e-9);
        let mut on_grid = false;
        let with_aperture = match aperture {
            None => false,
            Some(p) => {
                let not_smooth =
                    |reason: &str| Error::NotDifferentiable { parameter: p.describe(), reason: reason.to_owned() };
                match lens.aperture_directions(lambda) {
                    None => false,
                    Some(Err(why)) => return Err(not_smooth(&why)),
                    Some(Ok(_)) => {
                        // over a [[fields]] list each point off axis asks them of its own pass
                        // (`point_aperture_on_grid`)
                        if scene.fields().is_empty() && radial_on_grid(scene, scene.field()) {
                            on_grid = true;
                        }
                        true
                    }
                }
            }
        };
        let line = if wavelength { crate::evaluate::detected_spectrum(scene).line() } else { None };
        let with_wavelength = match line.and_then(|l| lens.wavelength_directions(l.center())) {
            None => false,
            Some(Err(why)) => {
                return Err(Error::NotDifferentiable {
                    parameter: Parameter::SpectrumCenter.describe(),
                    reason: format!("the line's wavelength moves this lens's orders in a way not followed yet: {why}"),
                });
            }
            Some(Ok(_)) => true,
        };
        if !(with_aperture || with_wavelength) {
            return Ok(None);
        }
        let own = |l: f64| lens.binary2_directions(l).and_then(|d| d.first().map(Vec::len)).unwrap_or(0);
        let mut bases = LaneBases::default();
        if with_aperture {
            bases.aperture = Some(own(lambda));
            bases.aperture_on_grid = if !on_grid {
                0
            } else if scene.field().is_on_axis() {
                3
            } else {
                5
            };
        }
        if let Some(l) = line.filter(|_| with_wavelength) {
            bases.wavelength = Some(own(l.center()) + if with_aperture { 3 } else { 0 });
        }
        let wrapped = ExtraLanes { inner: scene.lens_arc(), aperture: with_aperture, wavelength: with_wavelength };
        Ok(Some((scene.clone().with_lens(std::sync::Arc::new(wrapped)), bases)))
    }

    fn wrap(&self, inner: std::sync::Arc<dyn optics::LensModel>) -> ExtraLanes {
        ExtraLanes { inner, aperture: self.aperture, wavelength: self.wavelength }
    }
}

impl optics::LensModel for ExtraLanes {
    fn f_number(&self) -> f64 {
        self.inner.f_number()
    }
    fn focal_length(&self) -> f64 {
        self.inner.focal_length()
    }
    fn orders(&self, wavelength_m: f64, field: optics::Field) -> Vec<optics::Order> {
        self.inner.orders(wavelength_m, field)
    }
    fn orders_into(&self, wavelength_m: f64, field: optics::Field, out: &mut Vec<optics::Order>) {
        self.inner.orders_into(wavelength_m, field, out)
    }
    fn efficiency(&self, wavelength_m: f64) -> f64 {
        self.inner.efficiency(wavelength_m)
    }
    fn transmission(&self, wavelength_m: f64) -> f64 {
        self.inner.transmission(wavelength_m)
    }
    fn breakpoints(&self) -> Vec<f64> {
        self.inner.breakpoints()
    }
    /// The lens's factored parts, each part's orders wrapped as well (a factored lens's
    /// directions are its own: the same pupils).
    fn factored_efficiency(&self) -> Option<optics::FactoredEfficiency> {
        let mut f = self.inner.factored_efficiency()?;
        for part in &mut f.parts {
            part.relative = std::sync::Arc::new(self.wrap(part.relative.clone()));
        }
        Some(f)
    }
    fn numerical_aperture(&self) -> f64 {
        self.inner.numerical_aperture()
    }
    fn design_wavelength(&self) -> Option<f64> {
        self.inner.design_wavelength()
    }
    fn design_wavelength_rates(&self, wavelength_m: f64, field: optics::Field) -> Option<Vec<[f64; 2]>> {
        self.inner.design_wavelength_rates(wavelength_m, field)
    }
    fn design_wavelength_inert(&self) -> bool {
        self.inner.design_wavelength_inert()
    }
    fn binary2_directions(&self, wavelength_m: f64) -> Option<Vec<Vec<optics::radial::RadialProfile>>> {
        let aperture = match self.aperture {
            true => Some(self.inner.aperture_directions(wavelength_m)?.ok()?),
            false => None,
        };
        let wavelength = match self.wavelength {
            true => Some(self.inner.wavelength_directions(wavelength_m)?.ok()?.1),
            false => None,
        };
        let orders = aperture.as_ref().map(Vec::len).or(wavelength.as_ref().map(Vec::len))?;
        let own = self.inner.binary2_directions(wavelength_m).unwrap_or_else(|| vec![Vec::new(); orders]);
        if own.len() != orders || wavelength.as_ref().is_some_and(|w| w.len() != orders) {
            return None;
        }
        let mut aperture = aperture.map(Vec::into_iter);
        let mut wavelength = wavelength.map(Vec::into_iter);
        Some(
            own.into_iter()
                .map(|mut lanes| {
                    if let Some(e) = aperture.as_mut().and_then(Iterator::next) {
                        lanes.extend(e);
                    }
                    if let Some(w) = wavelength.as_mut().and_then(Iterator::next) {
                        lanes.extend(w);
                    }
                    lanes
                })
                .collect(),
        )
    }
    fn aperture_directions(&self, wavelength_m: f64) -> Option<optics::ApertureDirections> {
        self.inner.aperture_directions(wavelength_m)
    }
    fn wavelength_directions(&self, wavelength_m: f64) -> Option<optics::WavelengthDirections> {
        self.inner.wavelength_directions(wavelength_m)
    }
    fn describe(&self) -> String {
        self.inner.describe()
    }
    fn affine_defocus(&self, field: optics::Field) -> Option<optics::AffineDefocus> {
        self.inner.affine_defocus(field)
    }
}

/// `(∂M̄/∂ln F#, ∂M̄/∂ln f0)` of a lens that gives its aperture directions (a phase lens,
/// docs/physics.md "Gradients"), from the lanes `[P, T, S]` the evaluation carried
/// (`all[base..base + 3]`: `∂M̄` along each) and one OTF value at Nyquist:
/// - `F#` moves each wavelength's normalized frequency `s = νλF#`: by parts
///   `(1/ν_N) ∫ P sign(O) ν ∂O/∂ν dν = P(ν_N)|O(ν_N)| − M̄ − P_ν`, as for the other families
///   (`P` the pixel MTF where the camera applies it, [`pixel_slope`]'s `P_ν` its sinc's term;
///   1 and 0 without it);
/// - `R = f0/(2F#)` moves the wavefront along `P + T` per unit `ln R` (f0 held), so
///   `∂M̄/∂ln F# = P(ν_N)|O(ν_N)| − M̄ − P_ν − (D_P + D_T)`;
/// - `f0` with `F#` held moves `R` with it, `s` not: the wavefront along `P + S`, so
///   `∂M̄/∂ln f0 = D_P + D_S` (the lanes' weights carry `P`).
fn aperture_lane_partials(
    scene: &Scene,
    e: &Evaluation,
    p: Parameter,
    all: Option<&[f64]>,
    base: Option<usize>,
    on_grid: Option<&[f64]>,
) -> Result<(f64, f64), Error> {
    // off axis on the FFT path, the oblique wave's path moves with R and f0 too
    // (docs/physics.md, "Gradients: the F-number and the focal length of a phase lens off axis")
    let on_grid = on_grid.and_then(|lanes| match *lanes {
        [d_p, d_t, d_s] => Some([d_p, d_t, d_s, 0.0, 0.0]),
        [d_p, d_t, d_s, d_or, d_o] => Some([d_p, d_t, d_s, d_or, d_o]),
        _ => None,
    });
    if let Some([d_p, d_t, d_s, d_or, d_o]) = on_grid {
        let edge = crate::evaluate::mtf_at(scene, &[e.nyquist_cyc_per_mm], &[])?.mtf[0];
        let slope = pixel_slope(scene, p)?;
        return Ok((edge - e.mean_mtf - slope - (d_p + d_t + d_or), d_p + d_s + d_o));
    }
    let lanes = base.and_then(|b| all.and_then(|a| a.get(b..b + 3)));
    let Some(&[d_p, d_t, d_s]) = lanes else {
        return Err(Error::NotDifferentiable {
            parameter: p.describe(),
            reason: "the radial engine did not carry the aperture's lanes here (an order through an iris, zones, a map or a table, or the FFT path)"
                .to_owned(),
        });
    };
    // with the pixel MTF the edge is P(ν_N)|O(ν_N)| and its sinc's term −P_ν joins the parts
    let edge = crate::evaluate::mtf_at(scene, &[e.nyquist_cyc_per_mm], &[])?.mtf[0];
    let slope = pixel_slope(scene, p)?;
    Ok((edge - e.mean_mtf - slope - (d_p + d_t), d_p + d_s))
}

/// `∂M̄/∂A_j` for every Binary 2 coefficient of the lens, as the evaluation computed them
/// (`d_binary2`: [`optics::Polychromatic::mean_mtf_and_binary2_gradient`], the radial engine's
/// OTF derivatives on the value's own spectral levels and frequency panels), or why there are
/// none.
fn binary2_mean_mtf(p: Parameter, d_binary2: Option<Vec<f64>>) -> Result<Vec<f64>, Error> {
    let not_smooth = |reason: &str| Error::NotDifferentiable { parameter: p.describe(), reason: reason.to_owned() };
    // the pixel MTF P(ν) does not move with the wavefront: it is in the frequency rule's
    // accepted weights, ∂M̄ = (1/ν_N) ∫ P sign(O) ∂O dν (and under a noise spectrum the
    // ASNR's lanes are taken again on the value's noise-weighted pass: `weigh_by_noise`)
    d_binary2.ok_or_else(|| {
        not_smooth(
            "the wavefront gradient (Binary 2 coefficients, spline knots, m = 0 Zernike terms) is computed for a \
             lens whose every order is a radial pupil: on axis on the radial engine (a band on the exact \
             per-frequency engine, or a line), and on the FFT path of a band (off axis, or with Zernike terms of \
             m ≠ 0); this scene's lens, spectrum or field is neither (a line spectrum's FFT grids, or an order \
             through an iris, zones, a map or a table)",
        )
    })
}

/// `(∂ln N, ∂M̄)` with respect to the centre and to the range of the Gaussian spectrum.
struct SpectralPartials {
    center: (f64, f64),
    range: (f64, f64),
}

/// The first Gaussian factor of a spectrum (a product's factors searched in order), and how many
/// there are.
fn gaussians(spectrum: &radiometry::Spectrum, found: &mut Vec<radiometry::Gaussian>) {
    match spectrum {
        radiometry::Spectrum::Gaussian(g) => found.push(*g),
        radiometry::Spectrum::Product(factors) => factors.iter().for_each(|f| gaussians(f, found)),
        _ => {}
    }
}

/// The derivatives of `ln N` and of the mean MTF with respect to the centre `c` and the range
/// `r = 2√2 σ` of the scene's Gaussian spectrum `G = p exp(−(λ − c)²/(2σ²))` (docs/physics.md,
/// "Gradients"). `∂ln G/∂c = (λ − c)/σ²` and `∂ln G/∂σ = (λ − c)²/σ³`, so with the detected
/// weights `ρ τ1` and their moments `A_k = ∫ ρ τ1 λ^k dλ`:
/// - `∂ln N/∂c = ⟨λ − c⟩/σ²`, `∂ln N/∂σ = ⟨(λ − c)²⟩/σ³` (the engine's spectral average);
/// - the normalized OTF `O = ∫ ρ τ1 OTF_λ / A_0` moves as `∂O/∂c = A_1 (O_1 − O_0)/(σ² A_0)` and
///   `∂O/∂σ = (A_2 (O_2 − O_0) − 2c A_1 (O_1 − O_0))/(σ³ A_0)`, where `O_k` is the polychromatic
///   OTF of the spectrum `ρ λ^k`: a Gaussian times a polynomial again, which the engine integrates
///   on its own product-integration rule with the same moments (the closed form where the value
///   has it). The differences lose `(c/σ)^k` of the engine's relative accuracy, so these OTFs are
///   taken at the tolerance times `(σ/c)²/10`;
/// - `∂M̄ = (1/ν_N) ∫ sign(O) ∂O dν` (times the pixel MTF where it applies) on 16-point
///   Gauss–Legendre panels split at the sign changes of `O` (the kink of `|O|`), doubled until
///   the two derivatives move by at most the tolerance times their size.
///
/// Where the OTF depends on direction on the exact 1-D engine (lateral colour, a decentred iris,
/// a PSF stack's complex slices) or the overlap engine, the lanes on the value's own nodes and
/// rules ([`spectral_lanes_on_value_rule`]); on the FFT path, the same combinations of the
/// complex OTFs along each direction ([`optics::Polychromatic::otf_along`]),
/// `∂|O| = Re(O* ∂O)/|O|` ([`modulus_derivative`]), on the value's rule over directions
/// ([`DirectionalRule`]), the engines at the value's sampling levels ([`spectral_engines`]).
fn spectral_partials(scene: &Scene, e: &Evaluation, p: Parameter) -> Result<SpectralPartials, Error> {
    spectral_partials_over(scene, e, p, None)
}

/// [`spectral_partials`] with each frequency's weight divided by `n(ν)` where `noise` is given:
/// the `∂M̄` parts are then `∂G`'s, `G = (1/ν_N) ∫ P |O| / n dν` (docs/physics.md, "Gradients
/// under a noise spectrum": `n` does not move with the spectrum). Under the noise weight the
/// lanes are taken on the engines of ρ, ρλ, ρλ² (not the value's own pass), and a top-hat
/// band's on the engines of its edges' single wavelengths ([`top_hat_partials`]).
fn spectral_partials_over(
    scene: &Scene,
    e: &Evaluation,
    p: Parameter,
    noise: Option<&optics::NoiseShape>,
) -> Result<SpectralPartials, Error> {
    let not_smooth = |reason: String| Error::NotDifferentiable { parameter: p.describe(), reason };
    let camera = scene.camera();
    let over_noise = |nu: f64| noise.map_or(1.0, |n| 1.0 / n.value(nu));
    let detected = crate::evaluate::detected_spectrum(scene);
    let mut found = Vec::new();
    gaussians(&detected, &mut found);
    if found.is_empty()
        && let Some(band) = top_hat(&detected)
    {
        return top_hat_partials(scene, e, &detected, band, noise);
    }
    let [g] = found[..] else {
        return Err(not_smooth(format!(
            "the spectral gradient needs exactly one Gaussian factor in the detected spectrum (spectrum.shape = \"gaussian\"); this scene has {}",
            found.len()
        )));
    };
    let (c, sigma) = (g.center(), g.sigma());
    let per_range = 1.0 / (2.0 * std::f64::consts::SQRT_2);
    if let Some(((d_ln_n_c, dc), (d_ln_n_s, ds))) =
        spectral_lanes_on_value_rule(scene, e, c, sigma).filter(|_| noise.is_none())
    {
        return Ok(SpectralPartials { center: (d_ln_n_c, dc), range: (d_ln_n_s * per_range, ds * per_range) });
    }
    let lens = scene.lens();
    let field = scene.field();
    let nyquist = e.nyquist_cyc_per_mm * 1e3;
    let mut settings = scene.options().settings();
    let tolerance = settings.tolerance;
    settings.tolerance = (0.1 * tolerance * (sigma / c).powi(2)).max(1e-13);
    // the FFT path and the overlap engine keep the value's own tolerance for their sampling and
    // quadrature (a tightened one would ask them for grids beyond reach); their spectral nodes
    // are tightened from it as the other engines' are from theirs (the differences O_k − O_0 of
    // engines whose nodes are not the same lose (c/σ)² of the nodes' accuracy)
    let engine_tolerance = settings.fft_tolerance.unwrap_or(tolerance).max(tolerance);
    settings.fft_tolerance = Some(engine_tolerance);
    settings.spectral_tolerance = Some((0.1 * engine_tolerance * (sigma / c).powi(2)).max(1e-13));
    let linear = radiometry::Spectrum::Linear { slope: 1.0 };
    let spectra = [
        detected.clone(),
        radiometry::Spectrum::product(vec![detected.clone(), linear.clone()]),
        radiometry::Spectrum::product(vec![detected, linear.clone(), linear]),
    ];
    let shared = optics::SharedGrids::new();
    let levels = spectral_engines(lens, &spectra, field, nyquist, settings, &shared)?;
    let engines = &levels[0].1;
    let a: Vec<f64> = engines.iter().map(optics::Polychromatic::total_weight).collect();
    let d_ln_n_c = engines[0].spectral_average(|l, _| (l - c) / (sigma * sigma));
    let d_ln_n_s = engines[0].spectral_average(|l, _| ((l - c) / sigma).powi(2)) / sigma;
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    if engines[0].direction_dependent() {
        // the complex OTFs of ρ, ρλ, ρλ² along each direction, ∂O/∂c and ∂O/∂σ the same
        // combinations as below, ∂|O| = Re(O* ∂O)/|O|, on the value's rule over directions;
        // on the FFT path each sampling level's, combined as the value's Richardson extrapolation
        let rule = DirectionalRule::of(scene, &engines[0], tolerance);
        let weights: Vec<Vec<f64>> =
            levels.iter().map(|(_, l)| l.iter().map(optics::Polychromatic::total_weight).collect()).collect();
        let [_, dc, ds] = rule.mean(nyquist, [1.0, c, sigma], &|nu, azimuth| {
            let pix = pixel.map_or(1.0, |p| optics::pixel_mtf(p, nu)) * over_noise(nu);
            let mut sum = [0.0; 3];
            for ((share, level), a) in levels.iter().zip(&weights) {
                let o = optics::Polychromatic::otf_along_together(level, nu, azimuth);
                let (d1, d2) = (o[1] - o[0], o[2] - o[0]);
                let dc = d1 * (a[1] / (sigma * sigma * a[0]));
                let ds = (d2 * a[2] - d1 * (2.0 * c * a[1])) / (sigma.powi(3) * a[0]);
                let o0 = [o[0].re, o[0].im];
                sum[0] += share * o[0].norm();
                sum[1] += share * modulus_derivative(o0, [dc.re, dc.im]);
                sum[2] += share * modulus_derivative(o0, [ds.re, ds.im]);
            }
            sum.map(|x| pix * x)
        });
        return Ok(SpectralPartials { center: (d_ln_n_c, dc), range: (d_ln_n_s * per_range, ds * per_range) });
    }
    // (O, ∂O/∂c, ∂O/∂σ) at ν, the pixel MTF on the derivatives
    let at = |nu: f64| -> (f64, f64, f64) {
        let o: Vec<f64> = engines.iter().map(|eng| eng.otf(nu)).collect();
        let pix = pixel.map_or(1.0, |p| optics::pixel_mtf(p, nu)) * over_noise(nu);
        let (d1, d2) = (o[1] - o[0], o[2] - o[0]);
        let dc = a[1] * d1 / (sigma * sigma * a[0]);
        let ds = (a[2] * d2 - 2.0 * c * a[1] * d1) / (sigma.powi(3) * a[0]);
        (o[0], pix * dc, pix * ds)
    };
    let [dc, ds] = sign_split_mean(
        nyquist,
        4,
        |nu| engines[0].otf(nu),
        |nu| {
            let (o, dc, ds) = at(nu);
            (o, [dc, ds])
        },
        |change, next| {
            // each derivative against its own scale: per relative change of c and of σ
            let change = (change[0] * c).abs().max((change[1] * sigma).abs());
            let size = (next[0] * c).abs().max((next[1] * sigma).abs()).max(e.mean_mtf);
            change <= tolerance * size
        },
    );
    Ok(SpectralPartials { center: (d_ln_n_c, dc), range: (d_ln_n_s * per_range, ds * per_range) })
}

/// `((∂ln N/∂c, ∂M̄/∂c), (∂ln N/∂σ, ∂M̄/∂σ))` of a Gaussian band `G = p exp(−(λ − c)²/(2σ²))`
/// where the OTF depends on direction and the value's engine is the exact 1-D one (lateral
/// colour, a decentred iris, a PSF stack's planes) or the overlap engine (docs/physics.md,
/// "Gradients: the spectrum where the OTF depends on direction"): the lanes on the value's own
/// spectral nodes and its own rules over ν and azimuth, `None` elsewhere (the FFT path, an OTF
/// that does not depend on direction: the caller's engines of ρ, ρλ, ρλ²).
///
/// `∂ln G/∂c = (λ − c)/σ²` and `∂ln G/∂σ = (λ − c)²/σ³` move each node's weight `w` (its
/// moment of `ρ τ`) by these factors, so with `u = λ − λ̄` about the nodes' mean `λ̄`
/// (`d = λ̄ − c`) and the engine's lanes `L₁ = Σ w u O_λ / Σ w`, `L₂ = Σ w (u² − ⟨u²⟩) O_λ / Σ w`
/// ([`optics::WavefrontDirection::SpectralMoment`]; each complex, the lateral colour's phase
/// included):
///
/// ```text
/// ∂O/∂c = L₁/σ²,   ∂O/∂σ = (L₂ + 2 d L₁)/σ³,   ∂|O| = Re(O* ∂O)/|O|
/// ```
///
/// (the normalization's term `−O ⟨∂ln G⟩` is in the centring: `Σ w u = 0`); no differences of
/// nearly equal OTFs, so nothing to tighten for cancellation. The lanes ride on the value's
/// pass: the tangential and sagittal means of the exact engine
/// ([`optics::Polychromatic::mean_mtf_along_and_gradient`]) or the nested rule over azimuth
/// ([`optics::Polychromatic::mean_mtf_over_azimuth_and_overlap_gradient`]), each with the
/// frequency rule's accepted nodes and weights. The spectral error: the lanes interpolate
/// `g(λ) O_λ` (`g` of degree ≤ 2) on the value's nodes, whose nested estimate holds `O_λ`'s
/// interpolation to the spectral share of the tolerance; a derivative per relative change of
/// `c` is `(c/σ) L₁/σ`, which carries that error times `c/σ` (the band's relative narrowness),
/// so the spectral rule is taken at `q` times the tolerance, `q = |∇| / ((c/σ) M̄)` with `|∇|`
/// the gradient per relative change of `c` and `σ`: first at `q = 0.1 σ/c`
/// ([`LANE_GRADIENT_SHARE`]: a gradient of at least a tenth of `M̄`), and where the gradient
/// found is smaller, again at its own `q` (at least `10⁻³ σ/c`); the other rules (frequency,
/// azimuth, the overlap quadrature) as the value's.
type BandPartials = ((f64, f64), (f64, f64));

/// The least size of the band's gradient per relative change of `c` and `σ`, relative to the
/// mean MTF, that the spectral lanes' first pass assumes ([`spectral_lanes_on_value_rule`]):
/// its spectral rule at this share of the tolerance over `c/σ`; a gradient found smaller takes
/// a second pass at its own ratio.
const LANE_GRADIENT_SHARE: f64 = 0.1;

fn spectral_lanes_on_value_rule(scene: &Scene, e: &Evaluation, c: f64, sigma: f64) -> Option<BandPartials> {
    // the overlap engine, the exact engine's complex sums (lateral colour, an iris's tilt), or
    // its tables whose tangential and sagittal curves differ (a direction-independent OTF has
    // the two means equal to the mean): no engine built for an OTF the lanes do not serve
    let engine = &e.numerics.engine;
    let directional_table = engine == "exact-1d" && e.mean_mtf_tangential != e.mean_mtf_sagittal;
    if !(engine.starts_with("overlap") || engine.starts_with("exact-1d, complex") || directional_table) {
        return None;
    }
    let field = scene.field();
    let detected = crate::evaluate::detected_spectrum(scene);
    let settings = scene.options().settings();
    let first = field.y_rad.atan2(field.x_rad);
    let directions = [optics::WavefrontDirection::SpectralMoment(1), optics::WavefrontDirection::SpectralMoment(2)];
    // (∂ln N/∂c, ∂M̄/∂c, ∂ln N/∂σ, ∂M̄/∂σ) on the engine of `settings`
    let pass = |settings: optics::Settings| -> Option<[f64; 4]> {
        on_value_engine(scene, &detected, settings, |poly| {
            if !poly.direction_dependent()
                || !matches!(poly.engine(), optics::Engine::Exact1d | optics::Engine::Overlap { .. })
            {
                return None;
            }
            // the value's mean over azimuth (its nested rule from the field direction)
            let lanes = poly.mean_mtf_over_azimuth_and_overlap_gradient(first, &directions)?.1;
            if poly.over_budget().is_some() {
                return None;
            }
            let (mean, _) = poly.node_wavelength_moments();
            let d = mean - c;
            let d_ln_n_c = poly.spectral_average(|l, _| (l - c) / (sigma * sigma));
            let d_ln_n_s = poly.spectral_average(|l, _| ((l - c) / sigma).powi(2)) / sigma;
            Some([d_ln_n_c, lanes[0] / (sigma * sigma), d_ln_n_s, (lanes[1] + 2.0 * d * lanes[0]) / sigma.powi(3)])
        })
    };
    // the spectral rule at `share` times the engine's tolerance (the scene's, or the overlap
    // engine's `fft_tolerance`)
    let tolerance = e.numerics.tolerance;
    let at = |share: f64| optics::Settings { spectral_tolerance: Some((share * tolerance).max(1e-14)), ..settings };
    let narrowness = c / sigma;
    let share = LANE_GRADIENT_SHARE / narrowness;
    let [nc, dc, ns, ds] = pass(at(share))?;
    // q: the gradient per relative change of c and σ against (c/σ) M̄
    let q = (c * dc).hypot(sigma * ds) / (narrowness * e.mean_mtf.abs().max(f64::MIN_POSITIVE));
    if q < share {
        let [nc, dc, ns, ds] = pass(at(q.max(1e-3 / narrowness)))?;
        return Some(((nc, dc), (ns, ds)));
    }
    Some(((nc, dc), (ns, ds)))
}

/// The engines of the spectra `spectra` (ρ, ρλ, ρλ²) with `settings`, as sampling levels with
/// their shares: one level of the three engines (share 1), except on the FFT path where the
/// first engine chose its sampling from the tolerance: there the others take its `N`
/// (`options.pupil_samples` fixed, so that every `O_k` is read on the same grids' sampling), and
/// where the value extrapolates the means at `N/2` and `N` (Richardson, order
/// [`optics::fft::RICHARDSON_ORDER`]), the three at `N/2` too, the levels' shares
/// `1 + 1/(2^p − 1)` and `−1/(2^p − 1)`: the derivative of the extrapolated mean is the
/// extrapolation of the levels' derivatives. The cost is that of the grids: about three times
/// the value's (the first engine's sampling choice, two more at `N`, three at `N/2`), less the
/// grids they share through `shared` ([`optics::SharedGrids`]: a spectral node at the same
/// wavelength and sampling is one grid for the three, and the first engine's own levels serve
/// the others' `N/2`).
fn spectral_engines<'a>(
    lens: &'a dyn optics::LensModel,
    spectra: &'a [radiometry::Spectrum],
    field: optics::Field,
    nyquist: f64,
    settings: optics::Settings,
    shared: &'a optics::SharedGrids,
) -> Result<Vec<(f64, Vec<optics::Polychromatic<'a>>)>, Error> {
    let build = |s: &'a radiometry::Spectrum, settings: optics::Settings| {
        optics::Polychromatic::with_shared_grids(lens, s, field, nyquist, None, settings, shared)
    };
    let first = build(&spectra[0], settings)?;
    let optics::Engine::Fft { pupil_samples, coarse, extrapolated, .. } = first.engine() else {
        let mut engines = vec![first];
        for s in &spectra[1..] {
            engines.push(build(s, settings)?);
        }
        return Ok(vec![(1.0, engines)]);
    };
    let at = |n: usize| optics::Settings { pupil_samples: Some(n), ..settings };
    let mut fine = vec![first];
    for s in &spectra[1..] {
        fine.push(build(s, at(pupil_samples))?);
    }
    match coarse.filter(|_| extrapolated && settings.pupil_samples.is_none()) {
        Some(half) => {
            let r = 1.0 / (2f64.powf(optics::fft::RICHARDSON_ORDER) - 1.0);
            let coarse = spectra.iter().map(|s| build(s, at(half))).collect::<Result<Vec<_>, _>>()?;
            shared.forget();
            Ok(vec![(1.0 + r, fine), (-r, coarse)])
        }
        None => {
            shared.forget();
            Ok(vec![(1.0, fine)])
        }
    }
}

/// `∂|O| = Re(O* ∂O)/|O|` for a complex OTF `O = [re, im]` moving by `∂O` (docs/physics.md,
/// "Gradients: the spectrum where the OTF depends on direction"): a cone at `O = 0`, where the
/// modulus has no derivative but is integrable across; there, and where `|O|` is below 1e-15
/// (rounding of an OTF normalized to 1 at ν = 0), 0 is taken (`|∂|O|| ≤ |∂O|` everywhere, so
/// the integrand stays bounded and the set of such frequencies has no measure).
fn modulus_derivative(o: [f64; 2], d: [f64; 2]) -> f64 {
    let modulus = o[0].hypot(o[1]);
    if modulus <= 1e-15 { 0.0 } else { (o[0] * d[0] + o[1] * d[1]) / modulus }
}

/// The value's rule over directions where the OTF depends on direction (metric's `evaluate`;
/// docs/physics.md, "Pupils without rotational symmetry"): a 2-D OTF (a sampled pupil's grid,
/// the overlap engine, a PSF stack's planes) takes the mean over azimuth by the nested trapezoid
/// rule from the field direction; a 1-D OTF with image shifts (lateral colour) the average of
/// the tangential and sagittal means.
struct DirectionalRule {
    /// the field direction `atan2(θy, θx)`, the first azimuth
    first: f64,
    /// the mean over azimuth (else tangential and sagittal)
    over_azimuth: bool,
    /// the relative tolerance of each rule: the scene's, or the engine's where looser (the FFT
    /// path's and the overlap engine's `fft_tolerance`)
    tolerance: f64,
}

impl DirectionalRule {
    fn of(scene: &Scene, engine: &optics::Polychromatic<'_>, tolerance: f64) -> DirectionalRule {
        let field = scene.field();
        DirectionalRule {
            first: field.y_rad.atan2(field.x_rad),
            over_azimuth: engine.has_pupil_grid() || engine.direction_dependent(),
            tolerance: tolerance.max(engine.tolerance()),
        }
    }

    /// `(1/ν_N) ∫_0^{ν_N} f(ν, φ) dν` averaged over the directions of the rule, for three
    /// integrands together (`f` gives them at `(ν, φ)`; the first is `P |O|`, the others its
    /// derivatives, each measured against its own `scale`, the key's size, so that they
    /// converge alike in relative sensitivity). In ν: composite 16-point Gauss–Legendre, from 4
    /// panels doubled until the three move by at most the tolerance times the largest (at most
    /// 1024 panels; the kink of `|O|` at a zero and the FFT grids' cell edges are integrated
    /// across, their error falling with the panels' width). Over azimuth: the trapezoid rule on
    /// [`optics::FIRST_AZIMUTHS`] azimuths from the field direction, doubled until it moves by at
    /// most [`optics::AZIMUTH_SHARE`] of the tolerance (at most [`optics::MAX_AZIMUTHS`]), as
    /// the value's; or the tangential and sagittal directions.
    fn mean(&self, nyquist: f64, scale: [f64; 3], f: &dyn Fn(f64, f64) -> [f64; 3]) -> [f64; 3] {
        self.mean_split(&[0.0, nyquist], scale, f)
    }

    /// [`mean`](Self::mean) over `[0, ν_N]` given as the ends of its pieces (`ends`, rising,
    /// `0` first and `ν_N` last), each piece its own composite rule with the same number of
    /// panels: an integrand with a jump at a piece's end (a noise table's row, where `n′` jumps)
    /// integrated to the rule's order, not across the jump.
    fn mean_split(&self, ends: &[f64], scale: [f64; 3], f: &dyn Fn(f64, f64) -> [f64; 3]) -> [f64; 3] {
        let nyquist = ends[ends.len() - 1];
        let measure = |x: [f64; 3]| x.iter().zip(&scale).map(|(v, s)| (v * s).abs()).fold(0.0, f64::max);
        let along = |azimuth: f64| -> [f64; 3] {
            let integrate = |panels: usize| {
                let mut sum = [0.0; 3];
                for piece in ends.windows(2) {
                    optics::quad::for_each_node(piece[0], piece[1], panels, |nu, w| {
                        let v = f(nu, azimuth);
                        for (s, v) in sum.iter_mut().zip(v) {
                            *s += w * v;
                        }
                    });
                }
                sum.map(|s| s / nyquist)
            };
            let mut panels = 4;
            let mut previous = integrate(panels);
            loop {
                panels *= 2;
                let next = integrate(panels);
                let change = measure(std::array::from_fn(|i| next[i] - previous[i]));
                previous = next;
                if change <= self.tolerance * measure(previous) || panels >= 1024 {
                    return previous;
                }
            }
        };
        let pi = std::f64::consts::PI;
        if !self.over_azimuth {
            let (t, s) = (along(self.first), along(self.first + 0.5 * pi));
            return std::array::from_fn(|i| 0.5 * (t[i] + s[i]));
        }
        let mut count = optics::FIRST_AZIMUTHS;
        let mut sum = [0.0; 3];
        for k in 0..count {
            let v = along(self.first + pi * k as f64 / count as f64);
            sum.iter_mut().zip(v).for_each(|(s, v)| *s += v);
        }
        let mut average = sum.map(|s| s / count as f64);
        while count < optics::MAX_AZIMUTHS {
            let mut added = [0.0; 3];
            for k in 0..count {
                let v = along(self.first + pi * (2 * k + 1) as f64 / (2 * count) as f64);
                added.iter_mut().zip(v).for_each(|(s, v)| *s += v);
            }
            count *= 2;
            let refined: [f64; 3] = std::array::from_fn(|i| 0.5 * average[i] + added[i] / count as f64);
            let change = measure(std::array::from_fn(|i| refined[i] - average[i]));
            average = refined;
            if change <= optics::AZIMUTH_SHARE * self.tolerance * measure(average) {
                break;
            }
        }
        average
    }
}

/// `(∂ln N/∂c, ∂ln N_T/∂c, ∂M̄/∂c)` for the wavelength `c` of the scene's line (docs/physics.md,
/// "Gradients: a line's wavelength"), per m. The line's weight `w` (its `peak · width` times the
/// detected spectrum's other factors at `c`: the radiance, the quantum efficiency, the photon
/// factor λ) moves as [`radiometry::Spectrum::line_weight_log_derivative`], and `N ∝ w τ(c)`,
/// `N_T ∝ w T(c)`: `∂ln N/∂c = ∂ln w/∂c + ∂ln τ/∂λ` (the lens's efficiency and transmission
/// constant in λ where an affine defocus or wavelength directions are given; their rates from
/// [`optics::LensModel::defocus_rates`] otherwise). The OTF is the lens's at `c` alone,
/// `H(νcF#; W(c)/c)`, so at a fixed frequency it moves
/// - by its normalized frequency `s = νcF#`: by parts, as for the F-number,
///   `(1/ν_N) ∫ P sign(O) ν ∂O/∂ν dν = P(ν_N)|O(ν_N)| − M̄ − (1/ν_N) ∫ ν P′ |O| dν`, per unit
///   `ln c`;
/// - by its wavefront: for a lens whose one order is the full pupil with a defocus `W020(λ)`
///   alone, affine in λ ([`optics::LensModel::affine_defocus`]: the chromatic lens on axis) or
///   with its rates given ([`optics::LensModel::defocus_rates`]: the refractive lens, a glass's
///   n′(λ)), `w = W020/λ` moves by `∂ln w/∂c = W020′/W020 − 1/c`,
///   so by `D_K ∂ln w/∂c` with `D_K = (1/ν_N) ∫ P sign(O) w ∂H/∂w dν` on the value's own rule
///   ([`optics::Polychromatic::mean_mtf_and_defocus_derivative`], as the F-number's); for a lens
///   that gives its wavelength directions ([`optics::LensModel::wavelength_directions`]: a phase
///   lens), by the radial engine's lanes along `δW = ∂W/∂λ − W/λ` (`all[base..]`, the value's
///   own rules, without the pixel MTF).
fn line_center_partials(
    scene: &Scene,
    e: &Evaluation,
    all: Option<&[f64]>,
    base: Option<usize>,
    pass: Option<&DefocusFound>,
) -> Result<(f64, f64, f64), Error> {
    let p = Parameter::SpectrumCenter;
    let not_smooth = |reason: String| Error::NotDifferentiable { parameter: p.describe(), reason };
    let camera = scene.camera();
    let detected = crate::evaluate::detected_spectrum(scene);
    let Some(line) = detected.line() else {
        return Err(not_smooth("the detected spectrum has no line".to_owned()));
    };
    let c = line.center();
    let d_ln_n = detected.line_weight_log_derivative().map_err(|why| not_smooth(format!("the photon count: {why}")))?;
    let lens = scene.lens();
    let field = scene.field();
    if let Some(base) = base {
        let edge = mtf_at(scene, &[e.nyquist_cyc_per_mm], &[])?.mtf[0];
        let Some(Ok((coefficients, _))) = lens.wavelength_directions(c) else {
            return Err(not_smooth("the lens gives no wavelength directions here".to_owned()));
        };
        let Some(lanes) = all.and_then(|a| a.get(base..base + coefficients.len())) else {
            return Err(not_smooth(
                "the radial engine did not carry the wavelength's lanes here (off axis, an order through an iris, \
                 zones, a map or a table, or the FFT path)"
                    .to_owned(),
            ));
        };
        let along: f64 = coefficients.iter().zip(lanes).map(|(k, d)| k * d).sum();
        return Ok((d_ln_n, d_ln_n, (edge - e.mean_mtf) / c + along));
    }
    // one tabulated order (a PSF stack, a tabulated OTF): the interpolation's slope in λ on the
    // table's own OTFs (docs/physics.md, "Gradients: a line's wavelength and a blackbody's
    // temperature", on a table)
    if let Some(t) = line_table::line_on_table(scene, c, None)? {
        return Ok((d_ln_n + t.ln_efficiency, d_ln_n + t.ln_transmission, t.mean));
    }
    // one order through a circular iris, decentred or not, on axis or off it: the line engine's
    // defocus lane over azimuth (docs/physics.md, "Gradients: a line's wavelength through an
    // iris")
    if let Some(iris) = line_through_iris(scene, None) {
        return Ok((
            d_ln_n + iris.rates.ln_efficiency,
            d_ln_n + iris.rates.ln_transmission,
            (iris.edge - iris.mean - iris.pixel) / c + iris.defocus * iris.alpha,
        ));
    }
    // off axis, one order whose only change with the field is its image shift
    // (`LensModel::image_shift_field_rates`: the chromatic lens's lateral colour): a line's one
    // order is one wavelength, whose shift is a phase exp(−2πi ν·Δ) of the whole OTF, so |O|, the
    // mean MTF and its derivative in c are the order's on axis (docs/physics.md, "Gradients: a
    // line's wavelength off axis")
    if !field.is_on_axis()
        && lens.image_shift_field_rates(c, field).is_some()
        && let ([o], [a]) = (&lens.orders(c, field)[..], &lens.orders(c, optics::Field::ON_AXIS)[..])
        && matches!((&o.pupil, &a.pupil), (optics::Pupil::Full, optics::Pupil::Full))
        && o.wavefront.is_defocus_only()
        && (o.wavefront.defocus_m, o.efficiency) == (a.wavefront.defocus_m, a.efficiency)
    {
        // (the value's pass gave the defocus lane where the shift is 0, at λ0: the OTF on axis)
        return line_center_partials(&scene.single_field(optics::Field::ON_AXIS), e, None, None, pass);
    }
    // off axis, several orders each turned by its own lateral colour (the harmonic lens): the
    // line engine's lanes over azimuth (docs/physics.md, "Gradients: several orders under a line
    // off axis")
    if !field.is_on_axis()
        && let Some(found) = line_center_orders_off_axis(scene, c, d_ln_n)
    {
        return Ok(found);
    }
    // the line's orders on its FFT grids: an annulus, Seidel or Zernike terms (`line_grids`)
    if let Some(found) = line_grids::line_center_on_grids(scene, c, d_ln_n)? {
        return Ok(found);
    }
    let family = lens.describe();
    let orders = lens.orders(c, field);
    let full = |o: &optics::Order| {
        matches!(o.pupil, optics::Pupil::Full)
            && o.wavefront.image_shift_m == [0.0, 0.0]
            && [o.wavefront.spherical_m, o.wavefront.coma_m, o.wavefront.astigmatism_m, o.wavefront.field_curvature_m]
                == [0.0; 4]
    };
    let nyquist = camera.nyquist();
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    let settings = scene.options().settings();
    // where the value's pass did not carry the lane: the value's engine exactly (its parts, its
    // settings), `lane` beside each OTF value, and P(ν_N)|O(ν_N)| from the same engine
    let own_engine = |lane: &dyn Fn(&optics::Polychromatic<'_>) -> Option<optics::DefocusDerivative>| {
        on_value_engine(scene, &detected, settings, |poly| {
            Some((lane(poly)?, crate::evaluate::nyquist_edge(poly, nyquist, pixel)))
        })
    };
    // several orders, each moving by its own rates (the harmonic lens): the order lane
    // L = (Σ_o [τ_o α_o w ∂H_o/∂w + τ_o′ H_o] − O Σ_o τ_o′)/Σ_o τ_o beside each OTF value
    if let Some(order_rates) = lens.order_wavelength_rates(c, field)
        && orders.iter().all(full)
        && let Some(rates) = order_lane_rates(scene, c)
    {
        let (found, edge) = match pass.filter(|f| f.order_lane) {
            Some(f) => (f.found, f.edge),
            None => own_engine(&|poly| poly.mean_mtf_and_order_lane(&rates))
                .ok_or_else(|| not_smooth(format!("{family}: the line's engine gives no order lane here")))?,
        };
        let efficiency: f64 = orders.iter().map(|o| o.efficiency).sum();
        let moved: f64 = order_rates.orders.iter().map(|r| r[1]).sum();
        return Ok((
            d_ln_n + moved / efficiency,
            d_ln_n + order_rates.ln_transmission,
            (edge - e.mean_mtf - found.pixel_slope) / c + found.defocus,
        ));
    }
    let plain = matches!(&orders[..], [o] if full(o));
    let rates = match lens.affine_defocus(field) {
        Some(a) => Some(optics::DefocusRates { defocus: a.w020_slope, ln_efficiency: 0.0, ln_transmission: 0.0 }),
        None => lens.defocus_rates(c, field),
    };
    if let Some(why) = line_table::off_design_band(lens, c) {
        return Err(not_smooth(format!("{family}: {why}")));
    }
    let Some(rates) = rates.filter(|_| plain) else {
        return Err(not_smooth(format!(
            "{family}: the line's wavelength is followed through the OTF for a lens whose one order is the full \
             pupil with a defocus affine in λ and constant efficiencies (the chromatic lens without Seidel terms, \
             on axis or off it, through a circular iris too), the refractive lens, the dispersion-engineered lens \
             inside its band, one tabulated order between its breakpoints (a PSF stack), the harmonic lens with a \
             constant transmission and the interleaved multiplexed lens (on axis, and off axis on the line's exact \
             1-D engine), and a phase lens on the radial engine; this lens's orders move with λ otherwise (Seidel \
             or Zernike terms, an efficiency or transmission table's slope), which is not followed yet"
        )));
    };
    // the value's own pass where it carried the defocus lane (the line engine); else the value's
    // engine exactly (its parts, its settings), the defocus lane beside each OTF value, and
    // P(ν_N)|O(ν_N)| from the same engine (a full centred pupil on axis: the OTF is real and the
    // same along every direction)
    let (found, edge) = match pass.filter(|f| !f.order_lane) {
        Some(f) => (f.found, f.edge),
        None => own_engine(&|poly| poly.mean_mtf_and_defocus_derivative())
            .ok_or_else(|| not_smooth(format!("{family}: the line's engine gives no defocus lane here")))?,
    };
    let w020 = orders[0].wavefront.defocus_m;
    // ∂H/∂w = 0 at w = 0 (H is even in w)
    let d_defocus = if w020 == 0.0 { 0.0 } else { found.defocus * (rates.defocus / w020 - 1.0 / c) };
    Ok((
        d_ln_n + rates.ln_efficiency,
        d_ln_n + rates.ln_transmission,
        (edge - e.mean_mtf - found.pixel_slope) / c + d_defocus,
    ))
}

/// `∂ln N_T` over a band with respect to the spectral parameter `p` (the centre or range of the
/// scene's Gaussian or top-hat band, or its blackbody's temperature), per m or per K as `p`
/// says: the transmitted light `N_T ∝ I_T = ∫ ρ T dλ` (paper SI eq. S14: eq. S8 with τ1 → T;
/// docs/physics.md, "Gradients: the transmitted light over a band") moves only through the
/// detected spectrum `ρ`, so its derivative is the photon count's with `T` in place of the
/// imaging orders' efficiency:
/// - a Gaussian factor `exp(−(λ − c)²/(2σ²))`: `∂ln N_T/∂c = ⟨λ − c⟩_T/σ²` and
///   `∂ln N_T/∂r = ⟨(λ − c)²⟩_T/(2√2 σ³)` (`r = 2√2 σ`), `⟨·⟩_T` the mean over `ρ T`;
/// - a blackbody: `∂ln N_T/∂T = ⟨g⟩_T`, `g = ∂ln B/∂T` ([`radiometry::Blackbody::log_derivatives`]);
/// - a top-hat `[a, b] = [c − r/2, c + r/2]`: the integral's limits (Leibniz), `∂I_T/∂b =
///   ρ(b) T(b)`, `∂I_T/∂a = −ρ(a) T(a)`; `∂/∂c = ∂/∂a + ∂/∂b`, `∂/∂r = (∂/∂b − ∂/∂a)/2`, over `I_T`.
///
/// The means are taken on the detected spectrum's own quadrature
/// ([`radiometry::Spectrum::quadrature_nodes`]: 16-point Gauss–Legendre panels 1σ wide over ±12σ
/// of a Gaussian, Wien-scaled panels and a mapped tail for a blackbody, cut at every breakpoint
/// of the spectrum), its panels also cut at the lens's breakpoints (the rows of its
/// transmission table, where `T` has a kink): numerator and denominator on the same nodes,
/// each exact to about 1e-15 relative for the piecewise smooth `ρ T g`.
fn transmitted_band_log_derivative(scene: &Scene, p: Parameter) -> Result<f64, Error> {
    let not_smooth = |reason: String| Error::NotDifferentiable { parameter: p.describe(), reason };
    let lens = scene.lens();
    let detected = crate::evaluate::detected_spectrum(scene);
    let nodes = detected.quadrature_nodes_cut_at(&lens.breakpoints());
    // ∫ ρ T f over the nodes, for each f of `rates`
    let over_transmitted = |rate: &dyn Fn(f64) -> f64| -> f64 {
        let (mut total, mut moved) = (0.0, 0.0);
        for node in &nodes {
            let weight = node.weight * lens.transmission(node.wavelength_m);
            total += weight;
            moved += weight * rate(node.wavelength_m);
        }
        moved / total
    };
    let found = if p == Parameter::Temperature {
        let mut sources = Vec::new();
        detected_blackbodies(&detected, &mut sources);
        let [source] = sources[..] else {
            return Err(not_smooth(format!("the detected spectrum has {} blackbody factors, not one", sources.len())));
        };
        over_transmitted(&|l| source.log_derivatives(l).1)
    } else {
        let mut found = Vec::new();
        gaussians(&detected, &mut found);
        match (&found[..], top_hat(&detected)) {
            ([], Some(band)) => {
                let total: f64 = nodes.iter().map(|n| n.weight * lens.transmission(n.wavelength_m)).sum();
                let density = |x: f64| detected.value(x) * lens.transmission(x) / total;
                let (d_a, d_b) = (-density(band.lo()), density(band.hi()));
                if p == Parameter::SpectrumCenter { d_a + d_b } else { 0.5 * (d_b - d_a) }
            }
            ([g], _) => {
                let (c, sigma) = (g.center(), g.sigma());
                if p == Parameter::SpectrumCenter {
                    over_transmitted(&|l| (l - c) / (sigma * sigma))
                } else {
                    over_transmitted(&|l| ((l - c) / sigma).powi(2) / sigma) / (2.0 * std::f64::consts::SQRT_2)
                }
            }
            _ => {
                return Err(not_smooth(format!(
                    "the transmitted light's spectral derivative needs exactly one Gaussian factor or one top-hat in the \
                     detected spectrum; this scene has {} Gaussian factors",
                    found.len()
                )));
            }
        }
    };
    if found.is_finite() {
        Ok(found)
    } else {
        Err(not_smooth("the transmitted light N_T is 0 over the band (the lens transmits nothing there)".to_owned()))
    }
}

/// The blackbody factors of a spectrum (a product's factors searched in order).
fn detected_blackbodies(spectrum: &radiometry::Spectrum, found: &mut Vec<radiometry::Blackbody>) {
    match spectrum {
        radiometry::Spectrum::Blackbody { source, .. } => found.push(*source),
        radiometry::Spectrum::Product(factors) => factors.iter().for_each(|f| detected_blackbodies(f, found)),
        _ => {}
    }
}

/// `(∂ln N/∂T, ∂M̄/∂T)` for the temperature `T` of the scene's blackbody source, per K
/// (docs/physics.md, "Gradients: a line's wavelength and a blackbody's temperature"), with
/// Planck's `g(λ) = ∂ln B/∂T = (x/T) eˣ/(eˣ − 1)`, `x = hc/(λkT)`
/// ([`radiometry::Blackbody::log_derivatives`]).
/// - Under a line: `∂ln N/∂T = g(c)` at the line's wavelength `c`, and the OTF is the lens's at
///   that one wavelength, whatever the weight: `∂M̄/∂T = 0`.
/// - Over a band: [`temperature_band_partials`].
fn temperature_partials(scene: &Scene, e: &Evaluation, p: Parameter) -> Result<(f64, f64), Error> {
    temperature_partials_over(scene, e, p, None)
}

/// [`temperature_partials`] with each frequency's weight divided by `n(ν)` where `noise` is
/// given (the `∂M̄` part then `∂G`'s; under a line it is 0 either way).
fn temperature_partials_over(
    scene: &Scene,
    e: &Evaluation,
    p: Parameter,
    noise: Option<&optics::NoiseShape>,
) -> Result<(f64, f64), Error> {
    let not_smooth = |reason: String| Error::NotDifferentiable { parameter: p.describe(), reason };
    let detected = crate::evaluate::detected_spectrum(scene);
    fn blackbodies(spectrum: &radiometry::Spectrum, found: &mut Vec<radiometry::Blackbody>) {
        match spectrum {
            radiometry::Spectrum::Blackbody { source, .. } => found.push(*source),
            radiometry::Spectrum::Product(factors) => factors.iter().for_each(|f| blackbodies(f, found)),
            _ => {}
        }
    }
    let mut found = Vec::new();
    blackbodies(&detected, &mut found);
    let [source] = found[..] else {
        return Err(not_smooth(format!("the detected spectrum has {} blackbody factors, not one", found.len())));
    };
    match detected.line() {
        Some(line) => Ok((source.log_derivatives(line.center()).1, 0.0)),
        None => temperature_band_partials(scene, e, &detected, source, noise).map_err(|e| match e {
            Error::NotDifferentiable { reason, .. } => not_smooth(reason),
            other => other,
        }),
    }
}

/// `(∂ln N/∂T, ∂M̄/∂T)` over a band, for the detected spectrum `ρ` holding the blackbody
/// `source` (docs/physics.md, "Gradients: a line's wavelength and a blackbody's temperature"):
/// `∂ρ/∂T = ρ g`, so with the detected weights `ρ τ`, `A_0 = ∫ ρ τ` and `A_g = ∫ ρ τ g`,
/// - `∂ln N/∂T = ⟨g⟩ = A_g/A_0` (the engine's spectral average);
/// - the normalized OTF `O = ∫ ρ τ OTF / A_0` moves as `∂O/∂T = (A_g/A_0)(O_g − O_0)`, where
///   `O_g` is the polychromatic OTF of the spectrum `ρ g` (`ρ` times the factor
///   [`radiometry::Spectrum::PlanckTemperatureRate`]): its own engine, on the rules the value's
///   spectrum takes (product integration, the panels, the FFT path), converged to its own
///   tolerance;
/// - `∂M̄/∂T = (1/ν_N) ∫ P sign(O) ∂O/∂T dν` ([`sign_split_mean`]).
///
/// The difference `O_g − O_0` is the OTF weighted by `g/⟨g⟩ − 1`, of size `s = std(g)/⟨g⟩` (the
/// relative spread of `g` over the band, from the detected spectrum's own quadrature): it loses
/// that factor of the engines' relative accuracy, so both OTFs are taken at the tolerance times
/// `s/10` (at least 1e-13).
///
/// Under a noise spectrum (`noise`) each frequency's weight is divided by `n(ν)`: the `∂M̄` part
/// is then `∂G`'s, on these engines (not the value's own pass).
fn temperature_band_partials(
    scene: &Scene,
    e: &Evaluation,
    detected: &radiometry::Spectrum,
    source: radiometry::Blackbody,
    noise: Option<&optics::NoiseShape>,
) -> Result<(f64, f64), Error> {
    let not_smooth = |reason: String| Error::NotDifferentiable { parameter: Parameter::Temperature.describe(), reason };
    let camera = scene.camera();
    if noise.is_none()
        && let Some(found) = temperature_on_value_rule(scene, e, detected, source)
    {
        return Ok(found);
    }
    let rate = |l: f64| source.log_derivatives(l).1;
    // the relative spread of g over the detected spectrum, std(g)/⟨g⟩
    let (mut w, mut m1, mut m2) = (0.0, 0.0, 0.0);
    for node in detected.quadrature_nodes() {
        let g = rate(node.wavelength_m);
        w += node.weight;
        m1 += node.weight * g;
        m2 += node.weight * g * g;
    }
    let spread = if w > 0.0 && m1 > 0.0 { ((m2 / w - (m1 / w).powi(2)).max(0.0)).sqrt() / (m1 / w) } else { 1.0 };
    if e.numerics.engine.starts_with("fft") {
        return temperature_on_fft_path(scene, e, detected, source, noise, spread);
    }
    let lens = scene.lens();
    let field = scene.field();
    let nyquist = e.nyquist_cyc_per_mm * 1e3;
    let mut settings = scene.options().settings();
    let tolerance = settings.tolerance;
    settings.tolerance = (0.1 * tolerance * spread.min(1.0)).max(1e-13);
    let spectra = [
        detected.clone(),
        radiometry::Spectrum::product(vec![detected.clone(), radiometry::Spectrum::PlanckTemperatureRate { source }]),
    ];
    let engines = spectra
        .iter()
        .map(|s| optics::Polychromatic::with_settings(lens, s, field, nyquist, None, settings))
        .collect::<Result<Vec<_>, _>>()?;
    let mean_rate = engines[1].total_weight() / engines[0].total_weight();
    let d_ln_n = engines[0].spectral_average(|l, _| rate(l));
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    if engines.iter().any(|e| e.direction_dependent() || e.has_pupil_grid()) {
        return temperature_over_directions(scene, &engines, mean_rate, noise, source.temperature())
            .map(|d_mtf| (d_ln_n, d_mtf))
            .ok_or_else(|| {
                not_smooth(
                    "source.temperature_k: the OTF depends on direction here through a sampled pupil outside the \
                     FFT path's own engines; the temperature's lanes over a band are computed for a rotationally \
                     symmetric OTF, over directions on the 1-D engines (lateral colour, a decentred iris, MTF \
                     tables) and a PSF stack's planes, and on the FFT path at the value's sampling"
                        .to_owned(),
                )
            });
    }
    let at = |nu: f64| -> (f64, [f64; 1]) {
        let (o, o_g) = (engines[0].otf(nu), engines[1].otf(nu));
        let pix = pixel.map_or(1.0, |p| optics::pixel_mtf(p, nu)) / noise.map_or(1.0, |n| n.value(nu));
        (o, [pix * mean_rate * (o_g - o)])
    };
    // per relative change of T, against the size the engines' accuracy is relative to
    let t = source.temperature();
    let scale = (d_ln_n * t * spread * e.mean_mtf).abs();
    // from 2 panels (32 points): the lane is as smooth in ν as the OTF between its sign
    // changes, and the doubling's own check decides where to stop (from 4 panels, as the
    // Gaussian's centre starts, the gradient took 2–3× as long on the paper's lens and
    // examples/tabulated.toml at 50 and 200 nm, its error no smaller)
    let [d_mtf] = sign_split_mean(
        nyquist,
        2,
        |nu| engines[0].otf(nu),
        at,
        |change, next| (change[0] * t).abs() <= tolerance * (next[0] * t).abs().max(scale),
    );
    Ok((d_ln_n, d_mtf))
}

/// `(∂ln N/∂T, ∂M̄/∂T)` over a band where the value's pupil is sampled on the FFT path (a phase
/// lens off axis, Zernike terms with m ≠ 0 outside the overlap engine, a phase map or a 2-D
/// library layout; docs/physics.md, "Gradients: a line's wavelength and a blackbody's
/// temperature"): the engines of `ρ` and `ρ g` (`g = ∂ln B/∂T`) as the Gaussian band's centre
/// takes those of `ρ`, `ρλ`, `ρλ²` there ([`spectral_engines`]): the grids at the value's
/// sampling (its `fft_tolerance`, the sampling fixed for the second engine at the first's `N`,
/// and the two levels of the value's Richardson extrapolation with their shares), their
/// spectral nodes at the engine's tolerance times `s/10` (`spread`, `s = std(g)/⟨g⟩`: the
/// difference `O_g − O` loses that factor). Along each direction `∂O/∂T = ⟨g⟩ (O_g − O)`
/// complex, `∂|O| = Re(O* ∂O)/|O|` ([`modulus_derivative`]), the pixel MTF and `1/n(ν)` under a
/// noise spectrum on the weight, on the value's rule over directions ([`DirectionalRule`], its ν
/// pieces cut at the noise table's rows); `∂ln N/∂T = ⟨g⟩`, the first engine's spectral average.
fn temperature_on_fft_path(
    scene: &Scene,
    e: &Evaluation,
    detected: &radiometry::Spectrum,
    source: radiometry::Blackbody,
    noise: Option<&optics::NoiseShape>,
    spread: f64,
) -> Result<(f64, f64), Error> {
    let camera = scene.camera();
    let nyquist = e.nyquist_cyc_per_mm * 1e3;
    let mut settings = scene.options().settings();
    let tolerance = settings.tolerance;
    // the grids' sampling at the value's own tolerance (a tightened one would ask for grids
    // beyond reach); the spectral nodes tightened from it by the spread
    let engine_tolerance = settings.fft_tolerance.unwrap_or(tolerance).max(tolerance);
    let tight = |t: f64| (0.1 * t * spread.min(1.0)).max(1e-13);
    settings.tolerance = tight(tolerance);
    settings.fft_tolerance = Some(engine_tolerance);
    settings.spectral_tolerance = Some(tight(engine_tolerance));
    let spectra = [
        detected.clone(),
        radiometry::Spectrum::product(vec![detected.clone(), radiometry::Spectrum::PlanckTemperatureRate { source }]),
    ];
    let shared = optics::SharedGrids::new();
    let levels = spectral_engines(scene.lens(), &spectra, scene.field(), nyquist, settings, &shared)?;
    let engines = &levels[0].1;
    let d_ln_n = engines[0].spectral_average(|l, _| source.log_derivatives(l).1);
    // ⟨g⟩ of each level: the ratio of its two engines' weights
    let rates: Vec<f64> = levels.iter().map(|(_, l)| l[1].total_weight() / l[0].total_weight()).collect();
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    let rule = DirectionalRule::of(scene, &engines[0], tolerance);
    let t = source.temperature();
    let [_, d_mtf, _] = rule.mean_split(&noise_row_ends(noise, nyquist), [1.0, t, 0.0], &|nu, azimuth| {
        let weight = pixel.map_or(1.0, |p| optics::pixel_mtf(p, nu)) / noise.map_or(1.0, |n| n.value(nu));
        let mut sum = [0.0; 3];
        for ((share, level), rate) in levels.iter().zip(&rates) {
            let o = optics::Polychromatic::otf_along_together(level, nu, azimuth);
            let d = (o[1] - o[0]) * rate;
            sum[0] += share * o[0].norm();
            sum[1] += share * modulus_derivative([o[0].re, o[0].im], [d.re, d.im]);
        }
        sum.map(|x| weight * x)
    });
    Ok((d_ln_n, d_mtf))
}

/// `∂M̄/∂T` over a band where the OTF depends on direction (docs/physics.md, "Gradients: a
/// line's wavelength and a blackbody's temperature"): along each direction the complex OTFs of
/// `ρ` and `ρ g` (`engines`, `g = ∂ln B/∂T`), `∂O/∂T = ⟨g⟩ (O_g − O)`, `∂|O| = Re(O* ∂O)/|O|`
/// ([`modulus_derivative`]), the pixel MTF and `1/n(ν)` under a noise spectrum on the weight, on
/// the value's rule over directions ([`DirectionalRule`], its ν pieces cut at the noise table's
/// rows), each measured per relative change of `T` (`temperature`). `None` for a sampled pupil
/// (the FFT path's is [`temperature_on_fft_path`], taken before these engines are built).
fn temperature_over_directions(
    scene: &Scene,
    engines: &[optics::Polychromatic<'_>],
    mean_rate: f64,
    noise: Option<&optics::NoiseShape>,
    temperature: f64,
) -> Option<f64> {
    // the overlap engine's OTF along a direction is its own quadrature at the engine's
    // (tightened) tolerance: as the 1-D engines', read along the rule's directions
    let sampled = |e: &optics::Polychromatic<'_>| {
        e.has_pupil_grid() && !e.has_psf_planes() && !matches!(e.engine(), optics::Engine::Overlap { .. })
    };
    if engines.iter().any(sampled) {
        return None;
    }
    let camera = scene.camera();
    let nyquist = camera.nyquist();
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    let rule = DirectionalRule::of(scene, &engines[0], scene.options().settings().tolerance);
    let [_, d_mtf, _] = rule.mean_split(&noise_row_ends(noise, nyquist), [1.0, temperature, 0.0], &|nu, azimuth| {
        let weight = pixel.map_or(1.0, |p| optics::pixel_mtf(p, nu)) / noise.map_or(1.0, |n| n.value(nu));
        let (o, o_g) = (engines[0].otf_along(nu, azimuth), engines[1].otf_along(nu, azimuth));
        let d = (o_g - o) * mean_rate;
        [weight * o.norm(), weight * modulus_derivative([o.re, o.im], [d.re, d.im]), 0.0]
    });
    Some(d_mtf)
}

/// `(∂ln N/∂T, ∂M̄/∂T)` over a band on the value's own pass, where the value's engine is the
/// per-frequency product rule (docs/physics.md, "Gradients: a line's wavelength and a
/// blackbody's temperature"): `∂ρ/∂T = ρ g`, so `∂ln N/∂T = ⟨g⟩` (the engine's spectral
/// average) and each OTF value's lane is its own spectral sum re-weighted by the centred rate
/// `g(λ) − ⟨g⟩` ([`optics::Polychromatic::mean_mtf_and_spectral_lanes`]), integrated with the
/// frequency rule's accepted weights. `None` on the other engines (the caller's engines of `ρ`
/// and `ρ g`).
fn temperature_on_value_rule(
    scene: &Scene,
    e: &Evaluation,
    detected: &radiometry::Spectrum,
    source: radiometry::Blackbody,
) -> Option<(f64, f64)> {
    if !product_rule_on_axis(scene, e) {
        return None;
    }
    on_value_engine(scene, detected, scene.options().settings(), |poly| {
        let d_ln_n = poly.spectral_average(|l, _| source.log_derivatives(l).1);
        let centred = move |l: f64| source.log_derivatives(l).1 - d_ln_n;
        let (_, lanes, _) = poly.mean_mtf_and_spectral_lanes(Some(&centred), false)?;
        if poly.over_budget().is_some() {
            return None;
        }
        Some((d_ln_n, lanes[0]))
    })
}

/// Whether the value's engine may be the per-frequency product rule, whose spectral lanes
/// ([`optics::Polychromatic::mean_mtf_and_spectral_lanes`]) ride on the value's own sums: the
/// exact 1-D engine on product-integration nodes, on axis (no engine is built for the others:
/// the FFT path's grids would cost seconds only to be refused).
fn product_rule_on_axis(scene: &Scene, e: &Evaluation) -> bool {
    scene.field().is_on_axis() && e.numerics.engine == "exact-1d" && e.numerics.spectral_interpolated
}

/// `(1/ν_N) ∫_0^{ν_N} sign(O) L_k dν` for the lanes `at(ν) = (O(ν), [L_k(ν)])` (the derivatives
/// of the OTF `O` at ν, times the pixel MTF where it applies), on 16-point Gauss–Legendre panels
/// of `[0, ν_N]` split at the sign changes of `otf` ([`sign_change_ends`]: the kink of |O| at a
/// zero meets a panel only at its ends), from `first` panels (the Gaussian's centre: 4) doubled
/// until `converged(change, next)` holds for the move `change` of the lanes' means between two
/// doublings, or 1024 panels.
fn sign_split_mean<const K: usize>(
    nyquist: f64,
    first: usize,
    otf: impl Fn(f64) -> f64,
    at: impl Fn(f64) -> (f64, [f64; K]),
    converged: impl Fn(&[f64; K], &[f64; K]) -> bool,
) -> [f64; K] {
    let integrate = |panels: usize| sign_split_integral(nyquist, panels, &otf, &at, |hi| 1e-15 * hi, None);
    let mut panels = first.max(1);
    let mut previous = integrate(panels);
    loop {
        panels *= 2;
        let next = integrate(panels);
        let change: [f64; K] = std::array::from_fn(|k| next[k] - previous[k]);
        previous = next;
        if converged(&change, &previous) || panels >= 1024 {
            return previous;
        }
    }
}

/// `(1/ν_N) ∫_0^{ν_N} P(ν) sign(O) L_k dν` on `panels` equal 16-point Gauss–Legendre panels of
/// `[0, ν_N]` split at the sign changes of `otf`, each bracketed to `width` ([`sign_change_ends`]),
/// for the lanes `at(ν) = (O(ν), [L_k(ν)])`; `P` the pixel MTF where `pixel` is its pitch, else 1.
/// The frequency rule of [`sign_split_mean`] (its doublings) and of [`reference_rule`] (its
/// own zero width and the pixel MTF).
fn sign_split_integral<const K: usize>(
    nyquist: f64,
    panels: usize,
    otf: impl Fn(f64) -> f64,
    at: impl Fn(f64) -> (f64, [f64; K]),
    width: impl Fn(f64) -> f64,
    pixel: Option<f64>,
) -> [f64; K] {
    let ends = sign_change_ends(nyquist, panels, otf, width);
    let mut sums = [0.0; K];
    for w in ends.windows(2) {
        let half = 0.5 * (w[1] - w[0]);
        if half <= 0.0 {
            continue;
        }
        let centre = 0.5 * (w[0] + w[1]);
        for &(x, wx) in optics::quad::rule() {
            let nu = centre + half * x;
            let (o, lanes) = at(nu);
            // the pixel's factor 1 where it does not apply leaves the weight as it is, bit for bit
            let weight = half * wx * pixel.map_or(1.0, |pitch| optics::pixel_mtf(pitch, nu));
            let sign = if o < 0.0 { -1.0 } else { 1.0 };
            for (s, l) in sums.iter_mut().zip(lanes) {
                *s += weight * sign * l;
            }
        }
    }
    sums.map(|s| s / nyquist)
}

/// The top-hat factor of a spectrum (itself or one factor of a product), if there is exactly one.
fn top_hat(spectrum: &radiometry::Spectrum) -> Option<radiometry::TopHat> {
    fn collect(spectrum: &radiometry::Spectrum, found: &mut Vec<radiometry::TopHat>) {
        match spectrum {
            radiometry::Spectrum::TopHat(t) => found.push(*t),
            radiometry::Spectrum::Product(factors) => factors.iter().for_each(|f| collect(f, found)),
            _ => {}
        }
    }
    let mut found = Vec::new();
    collect(spectrum, &mut found);
    match found[..] {
        [t] => Some(t),
        _ => None,
    }
}

/// The derivatives of `ln N` and of the mean MTF with respect to the centre `c` and the range
/// `r` of a top-hat band `[a, b] = [c − r/2, c + r/2]` (docs/physics.md, "Gradients: a top-hat's
/// edges"): the edges are the integrals' limits, so by Leibniz's rule, with `D = ∫_a^b ρ Σ_o τ_o dλ`
/// the detected weight and `T_x = ρ(x) Σ_o τ_o(x)` its density at an edge,
/// - `∂ln N/∂b = T_b/D`, `∂ln N/∂a = −T_a/D`;
/// - the normalized OTF `O = ∫_a^b ρ Σ_o τ_o H_o dλ / D` moves as `∂O/∂b = (T_b/D)(O_b − O)` and
///   `∂O/∂a = −(T_a/D)(O_a − O)`, `O_x` the OTF at the single wavelength `x` (the line engine);
/// - `∂M̄/∂b = (T_b/D)((1/ν_N) ∫ P sign(O) O_b dν − M̄)`, as `(1/ν_N) ∫ P sign(O) O dν = M̄`;
/// - `∂/∂c = ∂/∂a + ∂/∂b`, `∂/∂r = (∂/∂b − ∂/∂a)/2`.
///
/// The integrals `∫ P sign(O) O_x dν` on 16-point Gauss–Legendre panels of `[0, ν_N]` split at
/// the sign changes of `O` (the kink of |O|), doubled until they move by at most the tolerance
/// times `M̄`. Where the OTF depends on direction, along each direction
/// `∂|O|/∂b = (T_b/D)(Re(O* O_b)/|O| − |O|)`, both means on the value's rule over directions
/// ([`DirectionalRule`]).
///
/// Under a noise spectrum (`noise`) each frequency's weight is divided by `n(ν)` (docs/physics.md,
/// "Gradients under a noise spectrum": `n` does not move with the band), so the means are the
/// weighted `G`'s: `∂G/∂b = (T_b/D)((1/ν_N) ∫ P sign(O) O_b / n dν − G)`, `G` on the same rule
/// (over directions, its pieces cut at the table's rows where `1/n` has its kinks).
fn top_hat_partials(
    scene: &Scene,
    e: &Evaluation,
    detected: &radiometry::Spectrum,
    band: radiometry::TopHat,
    noise: Option<&optics::NoiseShape>,
) -> Result<SpectralPartials, Error> {
    if noise.is_none()
        && let Some(found) = top_hat_on_value_rule(scene, e, detected, band)
    {
        return Ok(found);
    }
    let over_noise = |nu: f64| noise.map_or(1.0, |n| 1.0 / n.value(nu));
    let lens = scene.lens();
    let field = scene.field();
    let nyquist = e.nyquist_cyc_per_mm * 1e3;
    let settings = scene.options().settings();
    let tolerance = settings.tolerance;
    let camera = scene.camera();
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    let whole = optics::Polychromatic::with_settings(lens, detected, field, nyquist, None, settings)?;
    let (a, b) = (band.lo(), band.hi());
    // each edge's single wavelength (a line of any weight: its OTF is normalized)
    let lines =
        [radiometry::Line::new(a, 1e-9, 1.0)?, radiometry::Line::new(b, 1e-9, 1.0)?].map(radiometry::Spectrum::Line);
    let at_a = optics::Polychromatic::with_settings(lens, &lines[0], field, nyquist, None, settings)?;
    let at_b = optics::Polychromatic::with_settings(lens, &lines[1], field, nyquist, None, settings)?;
    // T_x/D: the detected density times the orders' efficiency at the edge, over the weight
    let density = |x: f64| {
        let efficiency: f64 = lens.orders(x, field).iter().map(|o| o.efficiency).sum();
        detected.value(x) * efficiency / whole.total_weight()
    };
    let (t_a, t_b) = (density(a), density(b));
    let (n_a, n_b) = (-t_a, t_b);
    if whole.direction_dependent() || at_a.direction_dependent() || at_b.direction_dependent() {
        // along each direction ∂O/∂b = (T_b/D)(O_b − O), so ∂|O|/∂b = (T_b/D)(Re(O* O_b)/|O| − |O|):
        // J = the mean of P|O| and I_x that of P Re(O* O_x)/|O|, on the same rule
        let rule = DirectionalRule::of(scene, &whole, settings.tolerance);
        let [j, i_a, i_b] = rule.mean_split(&noise_row_ends(noise, nyquist), [1.0; 3], &|nu, azimuth| {
            let o = whole.otf_along(nu, azimuth);
            let pix = pixel.map_or(1.0, |p| optics::pixel_mtf(p, nu)) * over_noise(nu);
            let (x_a, x_b) = (at_a.otf_along(nu, azimuth), at_b.otf_along(nu, azimuth));
            let o0 = [o.re, o.im];
            [
                pix * o.norm(),
                pix * modulus_derivative(o0, [x_a.re, x_a.im]),
                pix * modulus_derivative(o0, [x_b.re, x_b.im]),
            ]
        });
        let (d_a, d_b) = (-t_a * (i_a - j), t_b * (i_b - j));
        return Ok(SpectralPartials { center: (n_a + n_b, d_a + d_b), range: (0.5 * (n_b - n_a), 0.5 * (d_b - d_a)) });
    }
    // (1/ν_N) ∫ P sign(O) O_x / n dν for x = a, b, and x = the band itself (the mean the
    // differences are taken from: under a noise spectrum the weighted G on this rule)
    let [i_a, i_b, j] = sign_split_mean(
        nyquist,
        8,
        |nu| whole.otf(nu),
        |nu| {
            let pix = pixel.map_or(1.0, |p| optics::pixel_mtf(p, nu)) * over_noise(nu);
            let o = whole.otf(nu);
            (o, [pix * at_a.otf(nu), pix * at_b.otf(nu), pix * o])
        },
        |change, _| {
            let weighted = if noise.is_some() { change[2].abs() } else { 0.0 };
            change[0].abs().max(change[1].abs()).max(weighted) <= tolerance * e.mean_mtf
        },
    );
    let j = if noise.is_some() { j } else { e.mean_mtf };
    let (d_a, d_b) = (-t_a * (i_a - j), t_b * (i_b - j));
    Ok(SpectralPartials { center: (n_a + n_b, d_a + d_b), range: (0.5 * (n_b - n_a), 0.5 * (d_b - d_a)) })
}

/// [`top_hat_partials`] on the value's own pass, where the value's engine is the per-frequency
/// product rule and the band's edges are its panels' ends (docs/physics.md, "Gradients: a
/// top-hat's edges"): the Chebyshev–Lobatto points of every level include the panels' ends, so
/// the value's own sums there are the edges' OTFs `O_a`, `O_b` (times the orders' efficiency),
/// and each OTF value carries `∂O/∂a = −(T_a/D)(O_a − O)` and `∂O/∂b = (T_b/D)(O_b − O)` beside
/// it ([`optics::Polychromatic::mean_mtf_and_spectral_lanes`] with its edge lanes), integrated
/// with the frequency rule's accepted weights; `∂ln N` as there. `None` on the other engines, or
/// where the band's edges are not the engine's ends (a Gaussian or a table narrower than the
/// band): the caller's engines of the edges' single wavelengths.
fn top_hat_on_value_rule(
    scene: &Scene,
    e: &Evaluation,
    detected: &radiometry::Spectrum,
    band: radiometry::TopHat,
) -> Option<SpectralPartials> {
    if !product_rule_on_axis(scene, e) {
        return None;
    }
    let (a, b) = (band.lo(), band.hi());
    on_value_engine(scene, detected, scene.options().settings(), |poly| {
        if poly.spectral_ends()? != (a, b) {
            return None;
        }
        let (_, lanes, _) = poly.mean_mtf_and_spectral_lanes(None, true)?;
        if poly.over_budget().is_some() {
            return None;
        }
        // T_x/D: the detected density times the orders' efficiency at the edge, over the weight
        let density = |x: f64| {
            let efficiency: f64 = scene.lens().orders(x, scene.field()).iter().map(|o| o.efficiency).sum();
            detected.value(x) * efficiency / poly.total_weight()
        };
        let (n_a, n_b) = (-density(a), density(b));
        let (d_a, d_b) = (lanes[0], lanes[1]);
        Some(SpectralPartials { center: (n_a + n_b, d_a + d_b), range: (0.5 * (n_b - n_a), 0.5 * (d_b - d_a)) })
    })
}

/// The value's own engine (metric's `evaluate`: the scene's lens and field, the camera's
/// Nyquist frequency and pixel MTF, the lens's factored parts of `detected`) with `settings`,
/// handed to `f`; `None` where it is not built or `f` gives none.
fn on_value_engine<T>(
    scene: &Scene,
    detected: &radiometry::Spectrum,
    settings: optics::Settings,
    f: impl FnOnce(&optics::Polychromatic<'_>) -> Option<T>,
) -> Option<T> {
    with_value_engine(scene, detected, settings, |poly| Ok(f(poly))).ok().flatten()
}

/// [`on_value_engine`] where the engine's construction error is the caller's to return.
fn with_value_engine<T>(
    scene: &Scene,
    detected: &radiometry::Spectrum,
    settings: optics::Settings,
    f: impl FnOnce(&optics::Polychromatic<'_>) -> Result<T, Error>,
) -> Result<T, Error> {
    let (lens, camera) = (scene.lens(), scene.camera());
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    let folded = crate::evaluate::Folded::of(lens, detected);
    let parts = folded.parts();
    let poly =
        optics::Polychromatic::with_parts(lens, detected, &parts, scene.field(), camera.nyquist(), pixel, settings)?;
    f(&poly)
}

/// `(∂M̄/∂ln F#, ∂M̄/∂ln f0)` for a lens whose every order is the full circular pupil with a
/// defocus `W020 ∝ K = f0/(8F#²)` alone (docs/physics.md, "Gradients"). Each wavelength's OTF
/// is `H(νλF#, W020/λ)` ([`optics::defocus_otf`]), so
/// - `F#` moves the normalized frequency: `∂O/∂ln F#` at fixed `K` is `ν ∂O/∂ν`, and by parts
///   `(1/ν_N) ∫_0^{ν_N} sign(O) ν ∂O/∂ν dν = |O(ν_N)| − M̄` (|O| is continuous through its
///   kinks): one OTF value at Nyquist and the evaluation's mean MTF;
/// - `K` moves every order's defocus in proportion: `∂O/∂ln K = Σ_λ w_λ Σ_o τ_o w_o ∂H/∂w_o /
///   Σ_λ w_λ Σ_o τ_o` ([`optics::defocus_otf_log_derivative`]), `D_K = (1/ν_N) ∫ sign(O) ∂O/∂ln K dν`;
/// - `∂ln K/∂ln F# = −2`, `∂ln K/∂ln f0 = 1`: `∂M̄/∂ln F# = |O(ν_N)| − M̄ − 2 D_K`, `∂M̄/∂ln f0 = D_K`.
///
/// `D_K` by composite 16-point Gauss–Legendre in λ (over the detected spectrum's support, split
/// at its and the lens's breakpoints; a Gaussian's tails cut at 9σ, where it is below 3e-18 of
/// its peak; a line at its wavelength) and in ν (panels split at the sign changes of `O`, the
/// kink of |O|): the λ rule doubled on 8 ν panels, then the ν rule on it, each until `D_K` moves
/// by at most the tolerance times `max(|D_K|, M̄)`. Its cost is that of these OTF pairs, not the
/// value's: on the paper's lens about 1 s in a debug build, 13 s for the harmonic lens's six
/// orders (`asnr gradient examples/harmonic.toml --wrt lens.f_number`).
///
/// Where the value's own engine gives `∂O/∂ln K` beside each OTF value (the closed form, a line,
/// the per-frequency product rule of the refractive and harmonic lenses and of the chromatic lens
/// under other spectra: [`defocus_on_value_rule`]), `D_K` rides on the value's rules instead, and
/// the pixel MTF is
/// followed (its term of the integration by parts); this function's own rule stays as the
/// reference ([`aperture_partials_by_own_rule`]).
fn aperture_partials(
    scene: &Scene,
    e: &Evaluation,
    p: Parameter,
    pass: Option<&DefocusFound>,
    overlap_lane: Option<f64>,
) -> Result<(f64, f64), Error> {
    // (the white ∂M̄; under a noise spectrum ∂G is `noise_weight::aperture_over_noise`'s)
    // a composite pupil of zones: its lanes on the FFT path (`segmented`)
    if let Some(found) = segmented::aperture_on_zones(scene, e, p)? {
        return Ok(found);
    }
    // a designer's phase map: its cells' edges and values on the FFT path (`map`)
    if let Some(found) = map::aperture_on_map(scene, e, p)? {
        return Ok(found);
    }
    // no wavefront error at any node (a true achromat): D_K = 0, no pass for it
    if pass.is_none()
        && let Some(found) = achromat::aperture_without_defocus(scene, e, p)?
    {
        return Ok(found);
    }
    if let Some(found) = defocus_on_value_rule(scene, e, pass)? {
        return Ok(found);
    }
    if let Some(found) = aperture_on_overlap(scene, e, overlap_lane) {
        return Ok(found);
    }
    if let Some(found) = aperture_through_iris(scene, e)? {
        return Ok(found);
    }
    if let Some(found) = aperture_off_axis(scene, e)? {
        return Ok(found);
    }
    if let Some(found) = aperture_on_grids(scene, e)? {
        return Ok(found);
    }
    // a line's orders on its FFT grids (`line_grids`)
    if let Some(found) = line_grids::aperture_on_line_grids(scene)? {
        return Ok(found);
    }
    aperture_partials_by_own_rule(scene, e, p)
}

/// `(∂M̄/∂ln F#, ∂M̄/∂ln f0)` on axis where the value's OTF is computed on the FFT grids from a
/// sampled pupil with the chromatic defocus `W020(λ) = K a(λ)`, `K ∝ f0/F#²` (docs/physics.md,
/// "Gradients: the F-number and the focal length on the FFT grids"): an annulus
/// (`lens.obscuration`), Seidel terms through an iris (decentred), Zernike terms on the full
/// circle. The pupil is in units of the aperture's radius: the obscuration, the iris's size and
/// decentre and the Seidel and Zernike coefficients (keys of their own) do not move with F# or
/// f0. So at fixed `K` each wavelength's OTF is a function of `s = νλF#`, and the F-number's
/// share at fixed pupils is the frequency scale's lane `D_s` (each grid's reading moving with
/// F# on the value's own fixed rule, [`optics::Polychromatic::mean_mtf_over_azimuth_scale_lane`];
/// by parts the continuous rule's `P(ν_N)|O(ν_N)|‾ − M̄ − P_ν`), and `K` moves every node's
/// defocus by itself: the lane `D_K` ([`optics::WavefrontDirection::Defocus`], forward mode
/// through the FFT on the value's grids, levels, frequencies and azimuths). So
/// `∂M̄/∂ln F# = D_s − 2 D_K` and `∂M̄/∂ln f0 = D_K`. `None` where the scene is not that (off
/// axis, a line, another engine, a lens that gives its own aperture directions).
fn aperture_on_grids(scene: &Scene, e: &Evaluation) -> Result<Option<(f64, f64)>, Error> {
    let (first, directions) = grid_lanes(scene, optics::WavefrontDirection::Defocus);
    with_sampled_grids(scene, e, |poly| {
        let Some((_, lanes)) = poly.mean_mtf_over_azimuth_and_gradient(first, &directions)? else {
            return Ok(None);
        };
        let Some(d_s) = poly.mean_mtf_over_azimuth_scale_lane(first) else { return Ok(None) };
        let d_k = lanes[0];
        // off axis the lateral colour's `Δ ∝ f0` (not F#): its lane in f0's
        let d_shift = lanes.get(1).copied().unwrap_or(0.0);
        Ok(Some((d_s - 2.0 * d_k, d_k + d_shift)))
    })
}

/// The first azimuth of the value's rule over azimuth (the field direction, `x` on axis) and the
/// FFT grids' lanes to read beside `lane` ([`aperture_on_grids`], [`design_wavelength_on_grids`]):
/// off axis the image shifts' scale ([`optics::WavefrontDirection::ImageShift`], the lateral
/// colour `Δ ∝ f0` moving with f0 and, but for a shift common to every node, with λ0).
pub(super) fn grid_lanes(scene: &Scene, lane: optics::WavefrontDirection) -> (f64, Vec<optics::WavefrontDirection>) {
    let field = scene.field();
    match field.is_on_axis() {
        true => (0.0, vec![lane]),
        false => (field.y_rad.atan2(field.x_rad), vec![lane, optics::WavefrontDirection::ImageShift]),
    }
}

/// `(∂M̄/∂ln F#, ∂M̄/∂ln f0)` off axis for a lens whose every order is the full circular pupil
/// (or a circular iris, decentred) with a defocus alone and an image shift, on the exact 1-D
/// engine the value takes (or the full circle with Seidel terms, on the overlap engine's mean
/// over azimuth: the same lanes, [`optics::Polychromatic::mean_mtf_over_azimuth_and_aperture_lanes`]): the chromatic lens's lateral colour `Δ = f0 tan θ (λ0/λ − 1)`, each
/// harmonic order's `f0 tan θ (pλ0/(mλ) − 1)` (docs/physics.md, "Gradients: the F-number and
/// the focal length off axis"). Along each of the value's azimuths φ (its rule over azimuth from
/// the field direction) each node's OTF is `D(νλF#/r, W020/λ) exp(−2πi ν u·(Δ + Δ_iris))` with
/// `W020 = K a(λ)`, `K ∝ f0/F#²`, `Δ ∝ f0` (not F#) and the iris's `Δ_iris = 4 F# W020 d`. So
/// at fixed `K` and `Δ` the OTF is `H(νF#, νΔ)`: `∂O/∂ln F# = ν ∂O/∂ν − ∂O/∂ln Δ`, and by parts
/// `(1/ν_N) ∫ P ν ∂_ν|O| dν = P(ν_N)|O(ν_N)| − M̄ − P_ν`. With the lanes `D_K`
/// ([`optics::WavefrontDirection::Defocus`], the iris's tilt with it) and `D_Δ = ∂M̄/∂ln Δ`
/// ([`optics::WavefrontDirection::ImageShift`]) on the value's adaptive frequency rule along
/// each azimuth, averaged over the value's azimuths (its nested rule) as the value is:
/// `∂M̄/∂ln F# = P(ν_N)|O(ν_N)|‾ − M̄ − P_ν − 2 D_K − D_Δ` and `∂M̄/∂ln f0 = D_K + D_Δ`.
/// `None` where the scene is not that (on axis, a line, another pupil or engine). Under a noise
/// spectrum this is the white mean's; the weighted mean's takes the same lanes with each
/// frequency's weight divided by `n(ν)` (`noise_weight::aperture_over_noise`).
fn aperture_off_axis(scene: &Scene, e: &Evaluation) -> Result<Option<(f64, f64)>, Error> {
    let lens = scene.lens();
    let field = scene.field();
    let camera = scene.camera();
    let detected = crate::evaluate::detected_spectrum(scene);
    // (the white ∂M̄ under a noise spectrum too; the weighted mean's lanes are
    // `noise_weight::aperture_over_noise`'s, on the same engine)
    if field.is_on_axis() {
        return Ok(None);
    }
    let lambda = e.mean_wavelength_nm * 1e-9;
    let orders = lens.orders(lambda, field);
    let circles = circular_defocus_orders(&orders);
    // a line's several orders, each turned by its own lateral colour, on the line's exact 1-D
    // engine: the same lanes on its nodes (docs/physics.md, "Gradients: the field point under a
    // line"); one order is a phase of the whole OTF, taken elsewhere
    let line = detected.as_line().is_some();
    if line && !(circles && orders.len() >= 2) {
        return Ok(None);
    }
    // the full circle with Seidel terms: the overlap engine's mean over azimuth
    let seidel = !orders.is_empty() && orders.iter().all(overlap_pupil) && orders.iter().any(beyond_defocus);
    if !(circles || seidel) {
        return Ok(None);
    }
    let nyquist = camera.nyquist();
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    let folded = crate::evaluate::Folded::of(lens, &detected);
    let parts = folded.parts();
    let settings = scene.options().settings();
    let Ok(poly) = optics::Polychromatic::with_parts(lens, &detected, &parts, field, nyquist, pixel, settings) else {
        return Ok(None);
    };
    let along_field = field.y_rad.atan2(field.x_rad);
    // the full circle with Seidel terms on the overlap engine, the circles with image shifts on
    // the exact 1-D engine: either way the value's mean over azimuth, the lanes on its nodes and
    // accepted weights (on the overlap engine the defocus lane on its own doubled spectral rule,
    // as on axis), and the by-parts edge averaged over the same azimuths
    let engine = poly.engine();
    let taken = if line {
        engine == (optics::Engine::Monochromatic { fft: None }) && poly.direction_dependent()
    } else if seidel {
        matches!(engine, optics::Engine::Overlap { .. })
    } else {
        engine == optics::Engine::Exact1d && !poly.has_pupil_grid() && poly.direction_dependent()
    };
    if !taken {
        return Ok(None);
    }
    let Some((found, d_shift)) = poly.mean_mtf_over_azimuth_and_aperture_lanes(along_field) else {
        return Ok(None);
    };
    let edge = poly.mtf_over_azimuth(nyquist, along_field);
    let d_k = found.defocus;
    Ok(Some((edge - e.mean_mtf - found.pixel_slope - 2.0 * d_k - d_shift, d_k + d_shift)))
}

/// `(∂M̄/∂ln F#, ∂M̄/∂ln f0)` on axis for a lens whose every order is a circular iris (decentred)
/// with a defocus alone, on the exact 1-D engine (docs/physics.md, "Gradients: the iris"). Each
/// node's OTF is `D(νλF#/r, W020 r²/λ) exp(−2πi ν·Δ)` with `Δ = 2 W020 d/NA = 4 F# W020 d`
/// (`optics::fft::reduce_decentred_circle`) and `W020 = K a(λ)`, `K ∝ f0/F#²`: at fixed `K`
/// the OTF along every azimuth is a function of `νF#` (the tilt's phase `−8πi νF# K a u·d`
/// too), so by parts, per azimuth and then averaged over the value's azimuths (its nested rule),
/// `∂M̄/∂ln F#|_K = |O(ν_N)|‾ − M̄`; and at fixed `νF#` every node moves with `ln K`
/// as `w ∂D/∂w` turned by its phase plus `−2πi ν u·Δ` times itself (the tilt scales with
/// `W020`): the lane `D_K` ([`optics::WavefrontDirection::Defocus`] on the exact engine, on the
/// value's adaptive rule along each azimuth). So `∂M̄/∂ln F# = |O(ν_N)|‾ − M̄ − 2 D_K` and
/// `∂M̄/∂ln f0 = D_K`. With the pixel MTF `P` (its sinc does not scale with F#) the parts give
/// `P(ν_N)|O(ν_N)|‾ − M̄ − P_ν`, `P_ν = (1/ν_N) ∫ ν P′ |O| dν` averaged over the same azimuths
/// (recorded in the same pass as the lane,
/// [`optics::Polychromatic::mean_mtf_over_azimuth_and_defocus_lane`]), and `D_K` carries `P` in
/// its weights. `None` where the scene is not that: off axis (the lateral colour's
/// `Δ ∝ f0 tan θ` is not a function of `νF#`: [`aperture_off_axis`]), another pupil, a line,
/// another engine.
fn aperture_through_iris(scene: &Scene, e: &Evaluation) -> Result<Option<(f64, f64)>, Error> {
    let lens = scene.lens();
    let field = scene.field();
    let camera = scene.camera();
    let detected = crate::evaluate::detected_spectrum(scene);
    // (the white ∂M̄ under a noise spectrum too: `noise_weight::aperture_over_noise` weighs it)
    if !field.is_on_axis() || detected.as_line().is_some() {
        return Ok(None);
    }
    let lambda = e.mean_wavelength_nm * 1e-9;
    let orders = lens.orders(lambda, field);
    let circles = !orders.is_empty()
        && orders.iter().all(|o| {
            matches!(&o.pupil, optics::Pupil::Aperture(a) if a.as_circle().is_some()) && o.wavefront.is_defocus_only()
        });
    if !circles {
        return Ok(None);
    }
    let nyquist = camera.nyquist();
    let folded = crate::evaluate::Folded::of(lens, &detected);
    let parts = folded.parts();
    let settings = scene.options().settings();
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    let Ok(poly) = optics::Polychromatic::with_parts(lens, &detected, &parts, field, nyquist, pixel, settings) else {
        return Ok(None);
    };
    if poly.engine() != optics::Engine::Exact1d || poly.has_pupil_grid() {
        return Ok(None);
    }
    // the value's rule over azimuth from the field direction (x on axis), the lane and the
    // pixel's term of the parts in the same pass
    let Some(found) = poly.mean_mtf_over_azimuth_and_defocus_lane(0.0) else {
        return Ok(None);
    };
    // P(ν_N)|O(ν_N)| over azimuth (P = 1 without the pixel MTF)
    let edge = poly.mtf_over_azimuth(nyquist, 0.0);
    Ok(Some((edge - e.mean_mtf - found.pixel_slope - 2.0 * found.defocus, found.defocus)))
}

/// `(∂M̄/∂ln F#, ∂M̄/∂ln f0)` of the chromatic lens with Seidel terms on axis, on the overlap
/// engine the value takes (docs/physics.md, "Gradients: the F-number and the focal length with
/// Seidel terms"). The Seidel coefficients are the wavefront's at the pupil's edge in µm, keys of
/// their own: the F-number and focal length leave them as they are. What moves is each
/// wavelength's normalized frequency `s = νλF#` (at fixed wavefront the OTF along every azimuth
/// is a function of `νF#`, so by parts, per azimuth and then averaged,
/// `(1/ν_N) ∫ P ν ∂_ν|O| dν = P(ν_N)|O(ν_N)| − M̄ − P_ν`) and the chromatic defocus
/// `W020 ∝ f0/F#²`, whose lane `D_K = ∂M̄/∂ln K` rides on the overlap quadrature's nodes
/// ([`optics::Polychromatic::mean_mtf_over_azimuth_and_defocus_lane`]): `∂M̄/∂ln F# =
/// P(ν_N)|O(ν_N)|‾ − M̄ − P_ν − 2 D_K` (the overbar the mean over azimuth) and `∂M̄/∂ln f0 = D_K`.
/// `None` where the scene is not that (off axis, where the lateral colour's phase `−2πiν·Δ` does
/// not scale with F#; an iris or a Zernike pupil; a line; another engine).
///
/// `lane`: `D_K` where the value's own pass gave it (the scene's wavefront directions with the
/// defocus lane after them, [`defocus_lane_on_overlap`]); without the pixel MTF it is taken as
/// it is (no second pass over the overlap quadrature), else the mean is taken again with the
/// lane and `|O|` beside it for `P_ν`.
fn aperture_on_overlap(scene: &Scene, e: &Evaluation, lane: Option<f64>) -> Option<(f64, f64)> {
    if !defocus_lane_on_overlap(scene) {
        return None;
    }
    let lens = scene.lens();
    let field = scene.field();
    let detected = crate::evaluate::detected_spectrum(scene);
    let camera = scene.camera();
    let nyquist = camera.nyquist();
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    let folded = crate::evaluate::Folded::of(lens, &detected);
    let parts = folded.parts();
    let settings = scene.options().settings();
    let poly = optics::Polychromatic::with_parts(lens, &detected, &parts, field, nyquist, pixel, settings).ok()?;
    if !matches!(poly.engine(), optics::Engine::Overlap { .. }) {
        return None;
    }
    let (d_k, pixel_slope) = match lane {
        Some(d_k) if pixel.is_none() => (d_k, 0.0),
        _ => {
            let found = poly.mean_mtf_over_azimuth_and_defocus_lane(0.0)?;
            (found.defocus, found.pixel_slope)
        }
    };
    let edge = poly.mtf_over_azimuth(nyquist, 0.0);
    let d_f = edge - e.mean_mtf - pixel_slope - 2.0 * d_k;
    // the lane is each node's value times i k W020 [ρ²(p₊) − ρ²(p₋)], at most L = k_max |W020|max
    // times it: where the gradient is small against L M̄ the spectral rule's error ε M̄ may move
    // it by up to L ε M̄. The engine takes the lane on its own spectral rule, each panel's next
    // nested level over the value's points (`Polychromatic::defocus_lane_nodes`), in the
    // value's pass; where it cannot (the reference panels, a panel past 65 points), the lane,
    // the edge and M̄ are taken again with the spectral rule at max(q, 10⁻⁴) ε, q = |∇|/(L M̄),
    // the other rules as they are (as the field angles' lanes, `refine_field_lanes`)
    if poly.defocus_lane_nodes().is_some() {
        return Some((d_f, d_k));
    }
    let bound = 2.0 * std::f64::consts::PI * poly.max_defocus() * lens.f_number() * poly.max_cutoff() * e.mean_mtf;
    let q = if bound > 0.0 { (d_f.hypot(d_k) / bound).max(1e-4) } else { 1.0 };
    if q < 1.0 {
        let tighter = optics::Settings { spectral_tolerance: Some(q * poly.tolerance()), ..settings };
        if let Ok(fine) = optics::Polychromatic::with_parts(lens, &detected, &parts, field, nyquist, pixel, tighter)
            && matches!(fine.engine(), optics::Engine::Overlap { .. })
            && let Some(found) = fine.mean_mtf_over_azimuth_and_defocus_lane(0.0)
            && fine.over_budget().is_none()
        {
            let edge = fine.mtf_over_azimuth(nyquist, 0.0);
            let d_k = found.defocus;
            return Some((edge - found.mean - found.pixel_slope - 2.0 * d_k, d_k));
        }
    }
    Some((d_f, d_k))
}

/// Whether the F-number's defocus lane is taken on the overlap engine ([`aperture_on_overlap`]):
/// on axis, a band (not a line), every order at the mean wavelength the full circle without an
/// image shift and some with a Seidel term, and the overlap engine allowed. Under a noise
/// spectrum this is the white mean's lane; the weighted mean's is taken on the value's
/// noise-weighted rules (`noise_weight::aperture_over_noise`).
fn defocus_lane_on_overlap(scene: &Scene) -> bool {
    let lens = scene.lens();
    let field = scene.field();
    let detected = crate::evaluate::detected_spectrum(scene);
    let options = scene.options().settings();
    if !field.is_on_axis() || detected.as_line().is_some() || !options.overlap || options.pupil_samples.is_some() {
        return false;
    }
    // the chromatic lens's pupil, Seidel terms and (on axis) image shifts are the same at every
    // wavelength: its design wavelength, or a wavelength of the spectrum
    let lambda = lens.design_wavelength().or_else(|| detected.gaussians().first().map(|g| g.center())).or_else(|| {
        let (lo, hi) = detected.support();
        (hi.is_finite() && hi > lo).then_some(0.5 * (lo + hi))
    });
    let Some(lambda) = lambda.filter(|l| *l > 0.0) else { return false };
    let orders = lens.orders(lambda, field);
    orders.iter().all(|o| overlap_pupil(o) && o.wavefront.image_shift_m == [0.0, 0.0])
        && orders.iter().any(beyond_defocus)
}

/// Whether the order's pupil is one the overlap engine takes as a polynomial wavefront: the full
/// circle, or the full circle with Zernike terms alone ([`optics::radial::RadialPupil::is_zernike_only`];
/// docs/physics.md, "Zernike terms on the overlap engine").
fn overlap_pupil(o: &optics::Order) -> bool {
    match &o.pupil {
        optics::Pupil::Full => true,
        optics::Pupil::Radial(p) => p.is_zernike_only(),
        _ => false,
    }
}

/// Whether the order's wavefront has more than a defocus: a Seidel term, or Zernike terms.
fn beyond_defocus(o: &optics::Order) -> bool {
    !o.wavefront.is_defocus_only() || matches!(&o.pupil, optics::Pupil::Radial(p) if !p.zernike_noll_m().is_empty())
}

/// `∂M̄/∂W` of Seidel term `t` (per µm) off axis where every Seidel term is zero (docs/physics.md,
/// "Gradients: Seidel terms at zero"): the value's exact 1-D engine has no lane along the Seidel
/// terms, so the mean over azimuth is taken again on the overlap engine with the terms at zero
/// (`optics::Settings::overlap_always`), from the field direction, forward mode on its nodes, as
/// the value with a term not zero is; both are the mean over azimuth of the same OTF, so the
/// value is continuous there and this is its derivative. The error control is
/// [`seidel_at_zero`]'s: first at the engine's tolerance, again at `max(q, 10⁻⁴) ε` where the
/// lane is small against its bound `L M̄`. `None` on axis, where some term is not zero, or where
/// the overlap engine does not take the scene (an iris, `options.overlap = false`,
/// `options.pupil_samples`).
fn seidel_at_zero_off_axis(scene: &Scene, e: &Evaluation, t: optics::SeidelTerm) -> Result<Option<f64>, Error> {
    let field = scene.field();
    // (the white ∂M̄ under a noise spectrum too: `noise_weight::seidel_at_zero_over_noise`
    // weighs it)
    if field.is_on_axis() {
        return Ok(None);
    }
    let first = field.y_rad.atan2(field.x_rad);
    let directions = [optics::WavefrontDirection::Seidel(t)];
    seidel_lane_at_zero(scene, e, &|poly| {
        poly.mean_mtf_over_azimuth_and_overlap_gradient(first, &directions).map(|(mean, d)| (mean.mean, d[0]))
    })
}

/// Whether every Seidel term of every order is zero at the band's mean wavelength.
fn seidel_terms_zero(scene: &Scene, e: &Evaluation) -> bool {
    scene.lens().orders(e.mean_wavelength_nm * 1e-9, scene.field()).iter().all(|o| {
        let w = &o.wavefront;
        [w.spherical_m, w.coma_m, w.astigmatism_m, w.field_curvature_m] == [0.0; 4]
    })
}

/// A Seidel term's lane where every term is zero ([`seidel_terms_zero`]), on the overlap engine
/// run at zero (`optics::Settings::overlap_always`): `lane` gives the engine's mean and the lane
/// (white or noise-weighted, along one azimuth or over them). Error control: first at the
/// engine's tolerance, again at `max(q, 10⁻⁴) ε` where the lane is small against its bound
/// `L · mean` (`L = 2π · 10⁻⁶ ν_c F#` per µm, `q = |lane|/(L · mean)`). `None` where some term is
/// not zero or the overlap engine does not take the scene (an iris, `options.overlap = false`,
/// `options.pupil_samples`) or runs over its budget.
fn seidel_lane_at_zero(
    scene: &Scene,
    e: &Evaluation,
    lane: &dyn Fn(&optics::Polychromatic) -> Option<(f64, f64)>,
) -> Result<Option<f64>, Error> {
    if !seidel_terms_zero(scene, e) {
        return Ok(None);
    }
    let field = scene.field();
    let lens = scene.lens();
    let detected = crate::evaluate::detected_spectrum(scene);
    let camera = scene.camera();
    let nyquist = camera.nyquist();
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    let folded = crate::evaluate::Folded::of(lens, &detected);
    let parts = folded.parts();
    // (the lane, the engine's tolerance, L · mean)
    let run = |settings: optics::Settings| -> Result<Option<(f64, f64, f64)>, Error> {
        let poly = optics::Polychromatic::with_parts(lens, &detected, &parts, field, nyquist, pixel, settings)
            .map_err(Error::Optics)?;
        if !matches!(poly.engine(), optics::Engine::Overlap { .. }) {
            return Ok(None);
        }
        let bound = 2.0 * std::f64::consts::PI * 1e-6 * poly.max_cutoff() * lens.f_number();
        let found = lane(&poly);
        if poly.over_budget().is_some() {
            return Ok(None);
        }
        Ok(found.map(|(mean, d)| (d, poly.tolerance(), bound * mean)))
    };
    let settings = optics::Settings { overlap_always: true, ..scene.options().settings() };
    let Some((lane, tolerance, bound)) = run(settings)? else { return Ok(None) };
    let q = if bound > 0.0 { (lane.abs() / bound).max(1e-4) } else { 1.0 };
    if q >= 1.0 {
        return Ok(Some(lane));
    }
    let tighter = optics::Settings { tolerance: (q * tolerance).max(1e-14), fft_tolerance: None, ..settings };
    Ok(Some(run(tighter)?.map_or(lane, |(lane, _, _)| lane)))
}

/// `[∂M̄/∂W040, ∂M̄/∂W220]` (per µm) where every Seidel term is zero and the OTF rotationally
/// symmetric (docs/physics.md, "Gradients: Seidel terms at zero"): on the closed form's own rule
/// where the value takes it ([`seidel_at_zero_closed_form`]); elsewhere the value's engine (the
/// exact 1-D rules) has no lane along ρ⁴, so the mean is taken again on the
/// overlap engine with the terms at zero (`optics::Settings::overlap_always`), along one azimuth
/// (both directions are rotationally symmetric, so every azimuth gives the same), forward mode on
/// its nodes (a line: its one wavelength, each order a node, as the line's value is). `None`
/// where the overlap engine does not take the scene (an iris, `options.overlap = false` or
/// `options.pupil_samples`).
///
/// Error control: a lane is each node's value times `i k [D(p₊) − D(p₋)]`, with `D` ∈ [0, 10⁻⁶]
/// per µm on the disc, so at most `L = 2π · 10⁻⁶/λ_min` (per µm) times the value, and an error
/// `ε M̄` of the value's rules may move it by up to `L ε M̄`. In focus the mean MTF is nearly
/// stationary in these terms (a narrow band: `|∂M̄| ≪ L M̄`), so the pass is run first at the
/// engine's tolerance `ε` (the overlap engine's: `options.fft_tolerance` unless the scene sets
/// `options.tolerance`) and, where `q = |∂M̄|/(L M̄) < 1`, again at `max(q, 10⁻⁴) ε` (as the
/// field angles' lanes are, `refine_field_lanes`): the gradient to the tolerance relative to
/// its own norm. With no terms beyond defocus the overlap engine's x integral is in closed form,
/// so either pass costs little (a 10 nm band at 1e-10: about 10 ms in a debug build).
fn seidel_at_zero(scene: &Scene) -> Result<Option<[f64; 2]>, Error> {
    let lens = scene.lens();
    let detected = crate::evaluate::detected_spectrum(scene);
    let camera = scene.camera();
    let nyquist = camera.nyquist();
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    let folded = crate::evaluate::Folded::of(lens, &detected);
    let parts = folded.parts();
    let directions = [
        optics::WavefrontDirection::Seidel(optics::SeidelTerm::Spherical),
        optics::WavefrontDirection::Seidel(optics::SeidelTerm::FieldCurvature),
    ];
    if let Some(lanes) = seidel_at_zero_closed_form(scene)? {
        return Ok(Some(lanes));
    }
    // (M̄, the lanes, the engine's tolerance, L M̄)
    type Pass = (f64, [f64; 2], f64, f64);
    let run = |settings: optics::Settings| -> Result<Option<Pass>, Error> {
        let poly = optics::Polychromatic::with_parts(lens, &detected, &parts, scene.field(), nyquist, pixel, settings)
            .map_err(Error::Optics)?;
        if !matches!(poly.engine(), optics::Engine::Overlap { .. }) {
            return Ok(None);
        }
        let bound = 2.0 * std::f64::consts::PI * 1e-6 * poly.max_cutoff() * lens.f_number();
        let found = poly.mean_mtf_along_and_gradient(0.0, &directions);
        if poly.over_budget().is_some() {
            return Ok(None);
        }
        Ok(found.map(|(mean, _, d)| (mean, [d[0], d[1]], poly.tolerance(), bound * mean)))
    };
    let settings = optics::Settings { overlap_always: true, ..scene.options().settings() };
    let Some((_, lanes, tolerance, bound)) = run(settings)? else { return Ok(None) };
    let norm = lanes.iter().map(|d| d * d).sum::<f64>().sqrt();
    let q = if bound > 0.0 { (norm / bound).max(1e-4) } else { 1.0 };
    if q >= 1.0 {
        return Ok(Some(lanes));
    }
    let tighter = optics::Settings { tolerance: (q * tolerance).max(1e-14), fft_tolerance: None, ..settings };
    Ok(run(tighter)?.map(|(_, lanes, _, _)| lanes).or(Some(lanes)))
}

/// [`seidel_at_zero`] on the closed form, where the value takes it: the lanes along `ρ⁴` and
/// `ρ²` beside each OTF value on the closed form's own rule in the pupil angle, integrated with
/// the frequency rule's accepted weights ([`optics::Polychromatic::mean_mtf_and_seidel_lanes`];
/// docs/physics.md, "Gradients: Seidel terms at zero"). `None` where the value's engine is not
/// the closed form, or the overlap engine would not take the scene beside zero
/// (`options.overlap = false`, `options.pupil_samples`).
///
/// Error control: the spectral integral is exact, so the cancellation between wavelengths that
/// makes `|∂M̄| ≪ L M̄` near focus is in closed form; the rules in t and ν hold the lanes about
/// as they hold the value (within 2.8 ε of the norm, measured at 1e-3 … 1e-8 over bands of
/// 2–200 nm). Where `q = |∂M̄|/(L M̄)` is below [`CLOSED_FORM_SEIDEL_Q`] (narrower bands, where
/// the gradient falls faster than the rules' errors: 1.1e-4 of the norm off on a 0.2 nm band at
/// 1e-6) the closed form is taken again at `max(q, 10⁻⁴) ε`.
fn seidel_at_zero_closed_form(scene: &Scene) -> Result<Option<[f64; 2]>, Error> {
    let lens = scene.lens();
    let detected = crate::evaluate::detected_spectrum(scene);
    let camera = scene.camera();
    let nyquist = camera.nyquist();
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    let folded = crate::evaluate::Folded::of(lens, &detected);
    let parts = folded.parts();
    // (M̄, the lanes per µm, the engine's tolerance, L M̄)
    let run = |settings: optics::Settings| -> Option<(f64, [f64; 2], f64, f64)> {
        let poly =
            optics::Polychromatic::with_parts(lens, &detected, &parts, scene.field(), nyquist, pixel, settings).ok()?;
        if poly.engine() != optics::Engine::ClosedForm {
            return None;
        }
        let (mean, lanes, _) = poly.mean_mtf_and_seidel_lanes()?;
        let bound = 2.0 * std::f64::consts::PI * 1e-6 * poly.max_cutoff() * lens.f_number() * mean;
        poly.over_budget().is_none().then_some((mean, lanes.map(|d| 1e-6 * d), poly.tolerance(), bound))
    };
    let settings = scene.options().settings();
    // beside zero the value is on the overlap engine only where it may take the scene (else on
    // the FFT path, whose sampling error steps the value at zero: refused by `seidel_at_zero`)
    if !settings.overlap || settings.pupil_samples.is_some() {
        return Ok(None);
    }
    let Some((_, lanes, tolerance, bound)) = run(settings) else { return Ok(None) };
    let norm = lanes.iter().map(|d| d * d).sum::<f64>().sqrt();
    let q = if bound > 0.0 { norm / bound } else { 1.0 };
    if q >= CLOSED_FORM_SEIDEL_Q {
        return Ok(Some(lanes));
    }
    let tighter = optics::Settings { tolerance: (q.max(1e-4) * tolerance).max(1e-14), ..settings };
    Ok(Some(run(tighter).map_or(lanes, |(_, lanes, _, _)| lanes)))
}

/// Below this ratio `q = |∇M̄|/(L M̄)` the closed form's Seidel lanes at zero are taken again at
/// a tighter tolerance ([`seidel_at_zero_closed_form`]).
const CLOSED_FORM_SEIDEL_Q: f64 = 1e-5;

/// `(∂M̄/∂ln F#, ∂M̄/∂ln f0)` ([`aperture_partials`]) on the value's own rules: the mean computed
/// again with `∂O/∂ln K` beside each OTF value ([`optics::Polychromatic::mean_mtf_and_defocus_derivative`]:
/// the closed form's lane on its rule in `t`, a line's orders, the per-frequency product rule's
/// `w ∂H/∂w` of its Bessel and asymptotic forms on the level each panel accepts; the frequency
/// rule's accepted weights, the pixel MTF `P` included), so that
/// `∂M̄/∂ln F# = P(ν_N)|O(ν_N)| − M̄ − (1/ν_N) ∫ ν P′ |O| dν − 2 D_K` and `∂M̄/∂ln f0 = D_K`
/// (docs/physics.md, "Gradients: the F-number and the focal length on the value's rule").
/// `None` where the engine has no such lane (the reference panels rule, the FFT path) or an order
/// is not the full circular pupil with a defocus alone. `pass`: the lane `∂O/∂ln K` and the end
/// term where the evaluation's own pass gave them (a line: [`evaluate_field_with_lanes`]); else
/// the mean is computed again with the lane.
fn defocus_on_value_rule(
    scene: &Scene,
    e: &Evaluation,
    pass: Option<&DefocusFound>,
) -> Result<Option<(f64, f64)>, Error> {
    if let Some(pass) = pass.filter(|f| !f.order_lane) {
        let d_k = pass.found.defocus;
        return Ok(Some((pass.edge - e.mean_mtf - pass.found.pixel_slope - 2.0 * d_k, d_k)));
    }
    let lens = scene.lens();
    let field = scene.field();
    let detected = crate::evaluate::detected_spectrum(scene);
    let lambda = match detected.as_line() {
        Some(line) => line.wavelength_m,
        None => e.mean_wavelength_nm * 1e-9,
    };
    let plain = lens.orders(lambda, field).iter().all(|o| {
        let w = &o.wavefront;
        matches!(o.pupil, optics::Pupil::Full)
            && w.image_shift_m == [0.0, 0.0]
            && [w.spherical_m, w.coma_m, w.astigmatism_m, w.field_curvature_m] == [0.0; 4]
    });
    if !plain {
        return Ok(None);
    }
    let camera = scene.camera();
    let nyquist = camera.nyquist();
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    // the value's engine exactly (its parts, its settings)
    let folded = crate::evaluate::Folded::of(lens, &detected);
    let parts = folded.parts();
    let settings = scene.options().settings();
    let Ok(poly) = optics::Polychromatic::with_parts(lens, &detected, &parts, field, nyquist, pixel, settings) else {
        return Ok(None);
    };
    let Some(found) = poly.mean_mtf_and_defocus_derivative() else { return Ok(None) };
    let edge = mtf_at(scene, &[e.nyquist_cyc_per_mm], &[])?.mtf[0];
    let d_k = found.defocus;
    Ok(Some((edge - e.mean_mtf - found.pixel_slope - 2.0 * d_k, d_k)))
}

/// `(∂M̄/∂ln F#, ∂M̄/∂ln f0)` of a lens whose every order is the full circular pupil with a
/// defocus alone (docs/physics.md, "Gradients"): with `reference`, by the slow reference rule (its own
/// Gauss–Legendre panels in λ and ν, split at the sign changes of `O`); else on the value's own
/// rule, `None` where the value's engine has no defocus lane. For the tests that hold the one
/// against the other.
pub fn aperture_mean_mtf_partials(scene: &Scene, e: &Evaluation, reference: bool) -> Result<Option<(f64, f64)>, Error> {
    if reference {
        aperture_partials_by_own_rule(scene, e, Parameter::FNumber).map(Some)
    } else {
        defocus_on_value_rule(scene, e, None)
    }
}

/// [`aperture_partials`] on this function's own Gauss–Legendre rules in λ and ν (described
/// above): where the value's engine has no defocus lane, and the reference the tests hold the
/// lane against.
pub(crate) fn aperture_partials_by_own_rule(scene: &Scene, e: &Evaluation, p: Parameter) -> Result<(f64, f64), Error> {
    // the defocus lane with the pixel MTF P(ν) in its weights, and P's own term of the
    // integration by parts in ν, P_ν = (1/ν_N) ∫ ν P′ |O| dν, on the value's engine (0 without
    // the pixel MTF; docs/physics.md, "Gradients: the F-number and the focal length")
    let d_k = defocus_lane_by_own_rule(scene, e, p, None)?;
    let pixel_slope = noise_weight::pixel_slope_white(scene, e, p)?;
    let edge = crate::evaluate::mtf_at(scene, &[e.nyquist_cyc_per_mm], &[])?.mtf[0];
    Ok((edge - e.mean_mtf - pixel_slope - 2.0 * d_k, d_k))
}

/// `D_K = (1/ν_N) ∫ sign(O) ∂O/∂ln K / n dν` on [`aperture_partials_by_own_rule`]'s own rule
/// (`n` the noise spectrum where given, else 1: under it each frequency's weight divided by
/// `n(ν)`, the table's kinks integrated across as the ν panels double).
fn defocus_lane_by_own_rule(
    scene: &Scene,
    e: &Evaluation,
    p: Parameter,
    noise: Option<&optics::NoiseShape>,
) -> Result<f64, Error> {
    let not_smooth = |reason: String| Error::NotDifferentiable { parameter: p.describe(), reason };
    let lens = scene.lens();
    let field = scene.field();
    let f_number = lens.f_number();
    let nyquist = e.nyquist_cyc_per_mm * 1e3;
    // each spectral node: (λ, ρ(λ) × the rule's weight, [(τ_o, w_o)] per order)
    type Node = (f64, f64, Vec<(f64, f64)>);
    let node = |lambda: f64, weight: f64| -> Result<Node, Error> {
        let mut orders = Vec::new();
        for o in lens.orders(lambda, field) {
            let w = &o.wavefront;
            let plain = matches!(o.pupil, optics::Pupil::Full)
                && w.image_shift_m == [0.0, 0.0]
                && [w.spherical_m, w.coma_m, w.astigmatism_m, w.field_curvature_m] == [0.0; 4];
            if !plain {
                return Err(not_smooth(
                    "the F-number and focal-length gradient is computed for a lens whose every order is the full \
                     circular pupil (or a circular iris) with a defocus alone (the chromatic, refractive and \
                     harmonic families, paraxial; off axis with their lateral colour on the exact 1-D engine, \
                     under a band or, on several orders, a line), or \
                     with Seidel or Zernike terms under a band (on the overlap engine), or on the FFT grids of a \
                     sampled pupil (an annulus, Seidel terms through an iris, Zernike terms) under a band (off axis \
                     with the lateral colour's shifts) or on axis under a line; this scene's lens has other pupils \
                     or aberrations, or is off axis, or under a noise spectrum there"
                        .to_owned(),
                ));
            }
            orders.push((o.efficiency, w.defocus_m / lambda));
        }
        Ok((lambda, weight, orders))
    };
    // O at ν on the nodes (for its sign and its zeros), and (O, ∂O/∂ln K)
    let value = |nodes: &[Node], nu: f64| -> f64 {
        let (mut total, mut o) = (0.0, 0.0);
        for (lambda, weight, orders) in nodes {
            for &(tau, w) in orders {
                total += weight * tau;
                o += weight * tau * optics::defocus_otf(nu * lambda * f_number, w);
            }
        }
        o / total
    };
    let at = |nodes: &[Node], nu: f64| -> (f64, f64) {
        let (mut total, mut o, mut d) = (0.0, 0.0, 0.0);
        for (lambda, weight, orders) in nodes {
            let s = nu * lambda * f_number;
            for &(tau, w) in orders {
                total += weight * tau;
                o += weight * tau * optics::defocus_otf(s, w);
                d += weight * tau * optics::defocus_otf_log_derivative(s, w);
            }
        }
        (o / total, d / total / noise.map_or(1.0, |n| n.value(nu)))
    };
    // the spectral rule doubled from 2 to 256 panels a piece on a coarse frequency rule (its
    // nodes reach 0.99 ν_N, where the defocus turns the OTF fastest in λ), then the frequency rule
    // to 1024 panels; the zeros to 1e-13 of ν_N: this rule's own (coarser than the value's 1e-15 of ν)
    let refinement = Refinement { lambda_panels: (2, 256), nu_panels: 1024, zero_width: &|_| 1e-13 * nyquist };
    // the pixel MTF on the lane's weight (the white callers refuse it before)
    let pixel = scene.camera().pixel_mtf().then_some(scene.camera().pixel_pitch());
    let (_, d_k) = reference_rule(scene, e, p, refinement, pixel, node, value, at)?;
    Ok(d_k)
}

/// `(∂ln N/∂ln λ0, ∂M̄/∂ln λ0)` for the design wavelength λ0 (docs/physics.md, "Gradients: the
/// design wavelength"): 0 where nothing the lens images with depends on λ0
/// ([`optics::LensModel::design_wavelength_inert`]: a phase lens's geometric phase); on the
/// value's own rules where its engine gives the lane
/// ([`design_wavelength_on_value_rule`]: the closed form, a line, the per-frequency product
/// rule; the pixel MTF in the frequency rule's weights; off axis where the field leaves the OTF
/// as on axis); off axis on the exact 1-D engine's lanes where the lateral colour moves with λ0
/// ([`design_wavelength_off_axis`]); else on the reference rule ([`design_wavelength_by_own_rule`]).
/// The white mean's: under a noise spectrum the weighted mean's is
/// [`design_wavelength_over_noise`]'s. Refused where none applies, naming why.
fn design_wavelength_partials(scene: &Scene, e: &Evaluation, p: Parameter) -> Result<(f64, f64), Error> {
    // nothing the lens images with depends on λ0 (a geometric phase given in radians): N, the
    // OTF and so every quantity do not move
    if scene.lens().design_wavelength_inert() {
        return Ok((0.0, 0.0));
    }
    if let Some(on_axis) = line_seen_on_axis(scene) {
        return design_wavelength_partials(&on_axis, e, p);
    }
    if let Some(found) = line_orders_off_axis(scene, None) {
        return Ok((found.rate, found.design - found.rate * found.mean + found.shift));
    }
    if let Some(found) = design_wavelength_on_value_rule(scene) {
        return Ok(found);
    }
    if let Some(found) = design_wavelength_off_axis(scene, e, None) {
        return Ok(found);
    }
    if let Some(found) = design_wavelength_on_grids(scene, e, None)? {
        return Ok(found);
    }
    if let Some(found) = design_wavelength_on_overlap(scene, e, None) {
        return Ok(found);
    }
    if let Some(found) = line_grids::design_wavelength_on_line_grids(scene, None)? {
        return Ok(found);
    }
    design_wavelength_by_own_rule(scene, e, p, None)
}

/// `f` on the engine the value takes where it is on the FFT grids of sampled pupils
/// ([`on_sampled_grids`]), through [`with_value_engine`]; `None` elsewhere (another scene, or
/// another engine).
fn with_sampled_grids<T>(
    scene: &Scene,
    e: &Evaluation,
    f: impl FnOnce(&optics::Polychromatic<'_>) -> Result<Option<T>, Error>,
) -> Result<Option<T>, Error> {
    let detected = crate::evaluate::detected_spectrum(scene);
    if !on_sampled_grids(scene, e, &detected) {
        return Ok(None);
    }
    with_value_engine(scene, &detected, scene.options().settings(), |poly| {
        if !matches!(poly.engine(), optics::Engine::Fft { .. }) {
            return Ok(None);
        }
        f(poly)
    })
}

/// Whether the value's OTF is on the FFT grids of sampled pupils with the chromatic defocus
/// alone moving with the aperture and the design wavelength ([`aperture_on_grids`],
/// [`design_wavelength_on_grids`]): on axis, a band, every order the full circle, an aperture
/// or a radial pupil without an image shift, and a lens that gives no aperture directions of
/// its own (a phase lens's are [`aperture_lane_partials`]').
fn on_sampled_grids(scene: &Scene, e: &Evaluation, detected: &radiometry::Spectrum) -> bool {
    let lens = scene.lens();
    let field = scene.field();
    if detected.as_line().is_some() || !e.numerics.engine.starts_with("fft") {
        return false;
    }
    let lambda = e.mean_wavelength_nm * 1e-9;
    if lens.aperture_directions(lambda).is_some() {
        return false;
    }
    // off axis the image shifts are the lateral colour's (the lens gives their field rates: its
    // orders change with the field through them alone)
    if !field.is_on_axis() && lens.image_shift_field_rates(lambda, field).is_none() {
        return false;
    }
    let orders = lens.orders(lambda, field);
    !orders.is_empty()
        && orders
            .iter()
            .all(|o| matches!(o.pupil, optics::Pupil::Full | optics::Pupil::Aperture(_) | optics::Pupil::Radial(_)))
}

/// `(∂ln N/∂ln λ0, ∂M̄/∂ln λ0)` on axis where the value's OTF is computed on the FFT grids of
/// sampled pupils ([`on_sampled_grids`]: an annulus, Seidel terms through an iris, Zernike
/// terms; docs/physics.md, "Gradients: the F-number and the focal length on the FFT grids"):
/// λ0 leaves `s = νλF#`, the pupil and the Seidel and Zernike terms as they are and moves each
/// node's defocus by `∂W020/∂ln λ0` and its efficiency by `∂τ/∂ln λ0`
/// ([`optics::LensModel::design_wavelength_rates`]), the lane `D_λ0`
/// ([`optics::WavefrontDirection::DesignWavelength`], forward mode through the FFT on the
/// value's grids, levels, frequencies and azimuths), so `∂M̄ = D_λ0 − r M̄` with
/// `r = ∂ln N/∂ln λ0` on the engine's nodes ([`optics::Polychromatic::design_signal_rate`]).
/// Under a noise spectrum (`noise`) each frequency's weight divided by `n(ν)` and `M̄` the
/// weighted mean, as the value's. `None` where the scene is not that or the lens gives no rates.
fn design_wavelength_on_grids(
    scene: &Scene,
    e: &Evaluation,
    noise: Option<&optics::NoiseShape>,
) -> Result<Option<(f64, f64)>, Error> {
    let (first, directions) = grid_lanes(scene, optics::WavefrontDirection::DesignWavelength);
    with_sampled_grids(scene, e, |poly| {
        let Some(rate) = poly.design_signal_rate() else { return Ok(None) };
        let found = match noise {
            None => poly.mean_mtf_over_azimuth_and_gradient(first, &directions)?,
            Some(n) => poly.mean_mtf_over_azimuth_over_noise_and_gradient(first, &directions, n)?,
        };
        let Some((mean, lanes)) = found else { return Ok(None) };
        let d_shift = lanes.get(1).copied().unwrap_or(0.0);
        Ok(Some((rate, lanes[0] - rate * mean.mean + d_shift)))
    })
}

/// `∂G/∂ln λ0` of the noise-weighted mean `G = (1/ν_N) ∫ P |O| / n dν` the ASNR takes under the
/// noise spectrum `noise` (docs/physics.md, "Gradients under a noise spectrum", "Gradients:
/// the design wavelength off axis"): 0 for a lens inert in λ0; off axis on the exact 1-D
/// engine's lanes with each frequency's weight divided by `n(ν)`
/// ([`design_wavelength_off_axis`]); on axis on the reference rule with the same weight
/// ([`design_wavelength_by_own_rule`], the pixel MTF in its weights). Refused where neither
/// applies, naming why.
fn design_wavelength_over_noise(
    scene: &Scene,
    e: &Evaluation,
    p: Parameter,
    noise: &optics::NoiseShape,
) -> Result<f64, Error> {
    if scene.lens().design_wavelength_inert() {
        return Ok(0.0);
    }
    if let Some(on_axis) = line_seen_on_axis(scene) {
        return design_wavelength_over_noise(&on_axis, e, p, noise);
    }
    if let Some(found) = line_orders_off_axis(scene, Some(noise)) {
        return Ok(found.design - found.rate * found.mean + found.shift);
    }
    if let Some((_, d)) = design_wavelength_off_axis(scene, e, Some(noise)) {
        return Ok(d);
    }
    if let Some((_, d)) = design_wavelength_on_grids(scene, e, Some(noise))? {
        return Ok(d);
    }
    if let Some((_, d)) = design_wavelength_on_overlap(scene, e, Some(noise)) {
        return Ok(d);
    }
    if let Some((_, d)) = line_grids::design_wavelength_on_line_grids(scene, Some(noise))? {
        return Ok(d);
    }
    design_wavelength_by_own_rule(scene, e, p, Some(noise)).map(|(_, d)| d)
}

/// The scene moved on axis where a line off axis sees its one order as on axis but for its
/// image shift (`LensModel::image_shift_field_rates`: the chromatic lens's lateral colour
/// `Δ = f0 tan θ (λ0/c − 1)`): one wavelength, so the shift is a phase `exp(−2πi ν·Δ)` of the
/// whole OTF whatever λ0 does to it, and `|O|`, N's rates and their derivatives in λ0 are the
/// on-axis order's (docs/physics.md, "Gradients: the design wavelength off axis", as "a line's
/// wavelength off axis"). `None` otherwise.
fn line_seen_on_axis(scene: &Scene) -> Option<Scene> {
    let lens = scene.lens();
    let field = scene.field();
    let c = crate::evaluate::detected_spectrum(scene).line()?.center();
    if field.is_on_axis() || lens.image_shift_field_rates(c, field).is_none() {
        return None;
    }
    let ([o], [a]) = (&lens.orders(c, field)[..], &lens.orders(c, optics::Field::ON_AXIS)[..]) else { return None };
    let same = matches!((&o.pupil, &a.pupil), (optics::Pupil::Full, optics::Pupil::Full))
        && o.wavefront.is_defocus_only()
        && (o.wavefront.defocus_m, o.efficiency) == (a.wavefront.defocus_m, a.efficiency);
    same.then(|| scene.single_field(optics::Field::ON_AXIS))
}

/// A line's lanes off axis on its several orders (docs/physics.md, "Gradients: several orders
/// under a line off axis"), from [`optics::Polychromatic::mean_mtf_over_azimuth_and_line_lanes`]
/// on the value's own engine: along each azimuth the mean `M̄` (of `P|O|`, or `P|O|/n` under a
/// noise spectrum), `D_λ0`, `D_Δ`, `D_K` and `P_ν`, averaged over the value's rule in azimuth;
/// `r = ∂ln N/∂ln λ0` on the line's node; and with white noise the end term
/// `P(ν_N) ⟨|O(ν_N, φ)|⟩_φ` over azimuth.
struct LineOrders {
    mean: f64,
    design: f64,
    shift: f64,
    defocus: f64,
    pixel: f64,
    rate: f64,
    edge: Option<f64>,
}

/// [`LineOrders`] for a line off axis whose several orders are each the full circular pupil with
/// a defocus alone, each turned by its own lateral colour (the harmonic lens `Δ_m = f0 tan θ
/// (pλ0/(mλ) − 1)`), on the line's exact 1-D engine; `None` otherwise (one order, which
/// [`line_seen_on_axis`] takes; an iris, Seidel terms, the FFT path; on axis).
fn line_orders_off_axis(scene: &Scene, noise: Option<&optics::NoiseShape>) -> Option<LineOrders> {
    let lens = scene.lens();
    let field = scene.field();
    let camera = scene.camera();
    let detected = crate::evaluate::detected_spectrum(scene);
    let c = detected.line()?.center();
    let orders = lens.orders(c, field);
    let full = orders.iter().all(|o| matches!(o.pupil, optics::Pupil::Full) && o.wavefront.is_defocus_only());
    if field.is_on_axis() || orders.len() < 2 || !full {
        return None;
    }
    let nyquist = camera.nyquist();
    on_value_engine(scene, &detected, scene.options().settings(), |poly| {
        let along_field = field.y_rad.atan2(field.x_rad);
        let ([mean, design, shift, defocus, pixel], _) =
            poly.mean_mtf_over_azimuth_and_line_lanes(along_field, noise)?;
        let rate = poly.design_signal_rate()?;
        let edge = noise.is_none().then(|| poly.mtf_over_azimuth(nyquist, along_field));
        Some(LineOrders { mean, design, shift, defocus, pixel, rate, edge })
    })
}

/// Whether the lens's orders at the line's wavelength `c` off axis are those on axis, each a
/// function of `λ/λ0` alone to rounding (`c ∂/∂c = −λ0 ∂/∂λ0` of each order's defocus and
/// efficiency), so that a line's wavelength moves them as the design wavelength does (the
/// harmonic lens): the condition of [`line_center_orders_off_axis`] and its weighted twin.
pub(super) fn orders_of_wavelength_ratio(scene: &Scene, c: f64) -> bool {
    let lens = scene.lens();
    let field = scene.field();
    let (Some(on_axis), Some(design)) =
        (lens.order_wavelength_rates(c, optics::Field::ON_AXIS), lens.design_wavelength_rates(c, field))
    else {
        return false;
    };
    let orders = lens.orders(c, field);
    let axis_orders = lens.orders(c, optics::Field::ON_AXIS);
    if on_axis.orders.len() != orders.len() || design.len() != orders.len() || axis_orders.len() != orders.len() {
        return false;
    }
    let against = |a: f64, b: f64| (a + b).abs() <= 1e-9 * a.abs().max(b.abs());
    on_axis.orders.iter().zip(&design).zip(orders.iter().zip(&axis_orders)).all(
        |(([d_w020, d_tau], [l_w020, l_tau]), (o, a))| {
            against(c * d_w020, *l_w020) && against(c * d_tau, *l_tau) && o.efficiency == a.efficiency
        },
    )
}

/// A line's one order through a circular iris (docs/physics.md, "Gradients: a line's wavelength
/// through an iris"), on the line's exact 1-D engine: `[M̄, D_K, P_ν]` over azimuth from the field
/// direction ([`optics::Polychromatic::line_mean_mtf_over_azimuth_and_defocus_lane`], white or
/// over `noise`), the end term `P(ν_N) ⟨|O(ν_N, φ)|⟩_φ`, the lens's rates in λ
/// ([`optics::LensModel::defocus_rates`]) and `α = ∂ln w/∂c = W020′/W020 − 1/c` (0 at
/// `W020 = 0`, where `|O|` is even in `W020`: the wavefront `W020 (r² + (2d/NA) x)` changes sign
/// whole).
pub(super) struct IrisLine {
    pub mean: f64,
    pub defocus: f64,
    pub pixel: f64,
    pub edge: f64,
    pub rates: optics::DefocusRates,
    pub alpha: f64,
}

/// [`IrisLine`] where the scene's line sees one order, a circular iris with a defocus alone whose
/// rates in λ the lens gives, on the line's exact 1-D engine; `None` otherwise (the full pupil,
/// which [`line_center_partials`] takes on its own lanes; several orders; Seidel terms; the FFT
/// path).
pub(super) fn line_through_iris(scene: &Scene, noise: Option<&optics::NoiseShape>) -> Option<IrisLine> {
    let lens = scene.lens();
    let field = scene.field();
    let detected = crate::evaluate::detected_spectrum(scene);
    let c = detected.line()?.center();
    let [o] = &lens.orders(c, field)[..] else { return None };
    if !matches!(&o.pupil, optics::Pupil::Aperture(a) if a.as_circle().is_some()) || !o.wavefront.is_defocus_only() {
        return None;
    }
    let rates = lens.defocus_rates(c, field)?;
    let w020 = o.wavefront.defocus_m;
    let alpha = if w020 == 0.0 { 0.0 } else { rates.defocus / w020 - 1.0 / c };
    let nyquist = scene.camera().nyquist();
    let along_field = field.y_rad.atan2(field.x_rad);
    on_value_engine(scene, &detected, scene.options().settings(), |poly| {
        let [mean, defocus, pixel] = poly.line_mean_mtf_over_azimuth_and_defocus_lane(along_field, noise)?;
        let edge = poly.mtf_over_azimuth(nyquist, along_field);
        Some(IrisLine { mean, defocus, pixel, edge, rates, alpha })
    })
}

/// `(∂ln N/∂c, ∂ln N_T/∂c, ∂M̄/∂c)` for the wavelength `c` of a line off axis on several orders
/// each turned by its own lateral colour (docs/physics.md, "Gradients: several orders under a
/// line off axis"), per m, `d_ln_n` the line weight's own rate. The lens's orders depend on the
/// wavelength through `λ/λ0` alone (the harmonic lens: each order's `W020_m`, `τ_m` and
/// `Δ_m + f0 tan θ ∝ λ0/λ`; checked on the rates the lens gives, `c ∂W020_o/∂c = −∂W020_o/∂ln λ0`
/// and `c ∂τ_o/∂c = −∂τ_o/∂ln λ0`), so moving `c` and `λ0` together by `1 + ε` holds the orders
/// and moves only `s = νcF#` (up) and `w_o = W020_o/c` (down):
///
/// ```text
/// ∂M̄/∂ln c = (P(ν_N)|O(ν_N)| − M̄ − P_ν) − D_Δ − D_K − ∂M̄/∂ln λ0
///          = (P(ν_N)|O(ν_N)| − M̄ − P_ν) − D_K − D_λ0 + r M̄ − 2 D_Δ
/// ```
///
/// (`ν ∂O/∂ν` at fixed `w_o`, `Δ_o` is the frequency scaling plus each order's turn
/// `−2πi ν u·Δ_o`, the image shifts' lane `D_Δ`; by parts as on axis; `∂M̄/∂ln λ0 = D_λ0 − r M̄
/// + D_Δ` as [`design_wavelength_off_axis`]'s), each term averaged over azimuth on the value's
/// rule ([`line_orders_off_axis`]); `∂ln N/∂c = ∂ln w/∂c + Σ_o τ_o′/Σ_o τ_o` and
/// `∂ln N_T/∂c = ∂ln w/∂c + ∂ln T/∂c`. `None` where the scene is not that.
fn line_center_orders_off_axis(scene: &Scene, c: f64, d_ln_n: f64) -> Option<(f64, f64, f64)> {
    if !orders_of_wavelength_ratio(scene, c) {
        return None;
    }
    let lens = scene.lens();
    let on_axis = lens.order_wavelength_rates(c, optics::Field::ON_AXIS)?;
    let orders = lens.orders(c, scene.field());
    let found = line_orders_off_axis(scene, None)?;
    let edge = found.edge?;
    let d_log_c =
        (edge - found.mean - found.pixel) - found.defocus - found.design + found.rate * found.mean - 2.0 * found.shift;
    let efficiency: f64 = orders.iter().map(|o| o.efficiency).sum();
    let moved: f64 = on_axis.orders.iter().map(|r| r[1]).sum();
    Some((d_ln_n + moved / efficiency, d_ln_n + on_axis.ln_transmission, d_log_c / c))
}

/// `(∂ln N/∂ln λ0, ∂M̄/∂ln λ0)` off axis for a lens whose every order is the full circular pupil
/// with a defocus alone and an image shift that moves with λ0 as the lateral colour does
/// (`Δ_o = f0 tan θ (λ0 a_o(λ) − 1)`: the chromatic and harmonic lenses,
/// [`optics::LensModel::design_wavelength_rates`]), on the exact 1-D engine the value takes
/// (docs/physics.md, "Gradients: the design wavelength off axis"). Along each azimuth φ each
/// node's OTF is `q τ_o H(νλF#, W020_o/λ) exp(−2πi ν u·Δ_o)` over `W = Σ q τ_o`; λ0 moves
/// `W020_o`, `τ_o` and `Δ_o` (by `Δ_o + f0 tan θ`, whose common translation turns `O` by one
/// phase and leaves `|O|` as it is), so
/// `∂|O|/∂ln λ0 = Re(O* L)/|O| − |O| ∂ln W/∂ln λ0 + ∂|O|/∂ln Δ`, `L` the nodes' own lane
/// ([`optics::WavefrontDirection::DesignWavelength`]) and the last the image shifts' scale
/// ([`optics::WavefrontDirection::ImageShift`]): `∂M̄ = D_λ0 − r M̄ + D_Δ` with
/// `r = ∂ln N/∂ln λ0` ([`optics::Polychromatic::design_signal_rate`]), all on the value's
/// adaptive rule along each of the value's azimuths and averaged over them; under a noise
/// spectrum (`noise`) each frequency's weight divided by `n(ν)` and `M̄` the weighted mean.
/// Through a decentred circular iris (on axis or off) the same lanes, each node's defocus
/// `W020 r²` and the iris's tilt `W020 (2d/NA)` moving with `W020` (docs/physics.md, "Gradients:
/// the design wavelength through an iris"). `None` where the scene is not that (on axis without
/// an iris, a line, another pupil or engine).
fn design_wavelength_off_axis(scene: &Scene, e: &Evaluation, noise: Option<&optics::NoiseShape>) -> Option<(f64, f64)> {
    let lens = scene.lens();
    let field = scene.field();
    let camera = scene.camera();
    let detected = crate::evaluate::detected_spectrum(scene);
    if detected.as_line().is_some() {
        return None;
    }
    let orders = lens.orders(e.mean_wavelength_nm * 1e-9, field);
    // every order the full circle or a circular iris with a defocus alone; on axis an iris
    // (decentred: the OTF depends on direction, its tilt 2 W020 d/NA moving with W020)
    let circles = circular_defocus_orders(&orders);
    let iris = orders.iter().any(|o| matches!(o.pupil, optics::Pupil::Aperture(_)));
    if !circles || (field.is_on_axis() && !iris) {
        return None;
    }
    let nyquist = camera.nyquist();
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    let folded = crate::evaluate::Folded::of(lens, &detected);
    let parts = folded.parts();
    let settings = scene.options().settings();
    let poly = optics::Polychromatic::with_parts(lens, &detected, &parts, field, nyquist, pixel, settings).ok()?;
    if poly.engine() != optics::Engine::Exact1d || poly.has_pupil_grid() || !poly.direction_dependent() {
        return None;
    }
    let rate = poly.design_signal_rate()?;
    let along_field = field.y_rad.atan2(field.x_rad);
    let (mean, d_design, d_shift, _) = poly.mean_mtf_over_azimuth_and_design_lanes(along_field, noise)?;
    Some((rate, d_design - rate * mean + d_shift))
}

/// `(∂ln N/∂ln λ0, ∂M̄/∂ln λ0)` (under a noise spectrum `noise` the weighted mean's `∂G`) where
/// every order is the full circle with Seidel or Zernike terms and the value is on the overlap
/// engine, on and off axis (docs/physics.md, "Gradients: the design wavelength with Seidel and
/// Zernike terms"): λ0 moves each order's defocus by `δW020 = ∂W020/∂ln λ0` and its efficiency
/// by `δτ` (`optics::LensModel::design_wavelength_rates`; the Seidel and Zernike terms are keys of
/// their own, in µm, and stay), the image shifts by their scale's lane, `s = νλF#` and the pixel
/// MTF held: the lane [`optics::WavefrontDirection::DesignWavelength`] (`ρ²` per metre times each
/// node's `δW020`, plus `δτ/τ` times its value) and the image shifts' on the overlap
/// quadrature's nodes and the value's accepted weights, averaged over the value's azimuths
/// ([`optics::Polychromatic::mean_mtf_over_azimuth_and_design_lanes`]), so that
/// `∂M̄/∂ln λ0 = D_λ0 − (∂ln N/∂ln λ0) M̄ + D_Δ`. Where the lane is small against its bound
/// `L M̄` (`L = 2π |δW020|max/λ_min`) the pass is taken again with the spectral rule at
/// `max(q, 10⁻⁴) ε`, `q = |∂M̄|/(L M̄)`. `None` where the scene is not that (a line, another
/// pupil, another engine, a lens without rates).
fn design_wavelength_on_overlap(
    scene: &Scene,
    e: &Evaluation,
    noise: Option<&optics::NoiseShape>,
) -> Option<(f64, f64)> {
    let lens = scene.lens();
    let field = scene.field();
    let camera = scene.camera();
    let detected = crate::evaluate::detected_spectrum(scene);
    let settings = scene.options().settings();
    if detected.as_line().is_some() || !settings.overlap || settings.pupil_samples.is_some() {
        return None;
    }
    let orders = lens.orders(e.mean_wavelength_nm * 1e-9, field);
    if orders.is_empty() || !orders.iter().all(overlap_pupil) || !orders.iter().any(beyond_defocus) {
        return None;
    }
    let nyquist = camera.nyquist();
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    let folded = crate::evaluate::Folded::of(lens, &detected);
    let parts = folded.parts();
    let along_field = field.y_rad.atan2(field.x_rad);
    // (∂ln N, ∂M̄, the engine's tolerance, L M̄)
    let run = |settings: optics::Settings| -> Option<(f64, f64, f64, f64)> {
        let poly = optics::Polychromatic::with_parts(lens, &detected, &parts, field, nyquist, pixel, settings).ok()?;
        if !matches!(poly.engine(), optics::Engine::Overlap { .. }) {
            return None;
        }
        let rate = poly.design_signal_rate()?;
        let (mean, d_design, d_shift, _) = poly.mean_mtf_over_azimuth_and_design_lanes(along_field, noise)?;
        if poly.over_budget().is_some() {
            return None;
        }
        let (lo, hi) = detected.support();
        let largest = [lo.max(1e-9), 0.5 * (lo + hi), hi.min(1e-5)]
            .iter()
            .filter_map(|&l| lens.design_wavelength_rates(l, field))
            .flatten()
            .map(|r| r[0].abs())
            .fold(0.0, f64::max);
        let bound = 2.0 * std::f64::consts::PI * largest / lo.max(1e-9) * mean;
        Some((rate, d_design - rate * mean + d_shift, poly.tolerance(), bound))
    };
    let (rate, d, tolerance, bound) = run(settings)?;
    let q = if bound > 0.0 { (d.abs() / bound).max(1e-4) } else { 1.0 };
    if q < 1.0 {
        let tighter = optics::Settings { spectral_tolerance: Some(q * tolerance), ..settings };
        if let Some((rate, d, _, _)) = run(tighter) {
            return Some((rate, d));
        }
    }
    Some((rate, d))
}

/// `(∂ln N/∂ln λ0, ∂M̄/∂ln λ0)` on the value's own engine and rules: the mean computed again with
/// `∂O/∂ln λ0` beside each OTF value ([`optics::Polychromatic::mean_mtf_and_design_lane`]), and
/// `∂ln N/∂ln λ0` on the engine's normalization nodes ([`optics::Polychromatic::design_signal_rate`]).
/// λ0 leaves `s = νλF#` and the pixel MTF as they are: `∂M̄ = (1/ν_N) ∫ P sign(O) ∂O dν`, the
/// lane integrated with the accepted weights, `P` in them. `None` where the engine has no such
/// lane.
fn design_wavelength_on_value_rule(scene: &Scene) -> Option<(f64, f64)> {
    let detected = crate::evaluate::detected_spectrum(scene);
    on_value_engine(scene, &detected, scene.options().settings(), |poly| {
        let found = poly.mean_mtf_and_design_lane()?;
        Some((poly.design_signal_rate()?, found.defocus))
    })
}

/// `∂M̄/∂ln λ0` of the design wavelength: with `reference`, by the slow reference rule
/// (docs/physics.md, "Gradients: the design wavelength"); else on the value's own rule, `None`
/// where the value's engine has no such lane. For the tests that hold the one against the other.
pub fn design_wavelength_mean_mtf_partial(
    scene: &Scene,
    e: &Evaluation,
    reference: bool,
) -> Result<Option<f64>, Error> {
    if reference {
        design_wavelength_by_own_rule(scene, e, Parameter::DesignWavelength, None).map(|(_, d)| Some(d))
    } else {
        Ok(design_wavelength_on_value_rule(scene).map(|(_, d)| d))
    }
}

/// `(∂ln N/∂ln λ0, ∂M̄/∂ln λ0)` for the design wavelength λ0 of a lens whose every order is the
/// full circular pupil with a defocus alone and that gives how each order moves with λ0
/// ([`optics::LensModel::design_wavelength_rates`]: `δW_o = ∂W020_o/∂ln λ0`,
/// `δτ_o = ∂τ_o/∂ln λ0`), on axis (docs/physics.md, "Gradients: the design wavelength"). Each
/// wavelength's OTF is `Σ_o τ_o H(νλF#, w_o)` with `w_o = W020_o/λ` ([`optics::defocus_otf`]);
/// λ0 leaves `s = νλF#` and ρ as they are, so at a fixed frequency
///
/// ```text
/// ∂O/∂ln λ0 = (∫ ρ Σ_o [τ_o ∂H/∂w (δW_o/λ) + δτ_o H_o] dλ − O ∫ ρ Σ_o δτ_o dλ) / ∫ ρ Σ_o τ_o dλ
/// ```
///
/// (`∂H/∂w = (w ∂H/∂w)/w` from [`optics::defocus_otf_log_derivative`], 0 at `w = 0` where `H` is
/// even in `w`), `∂M̄ = (1/ν_N) ∫ sign(O) ∂O dν`, and `∂ln N/∂ln λ0 = ∫ ρ Σ δτ_o / ∫ ρ Σ τ_o`,
/// both on the reference rule's own Gauss–Legendre panels in λ and ν ([`reference_rule`]: the λ
/// panels doubled, then the ν panels, each until the integral moves by at most the tolerance
/// times `max(|∂M̄|, M̄)`; the ν panels split at the sign changes of `O`, the kink of `|O|`).
/// The reference where the value's engine has no lane; under a noise spectrum (`noise`) the
/// noise-weighted mean's `∂G`, each frequency's weight divided by `n(ν)` and the pixel MTF in the
/// weights; refused with the pixel MTF on the white mean (not followed on this rule), off axis
/// (the lateral colour moves with λ0: [`design_wavelength_off_axis`]), and for the other
/// families naming why.
fn design_wavelength_by_own_rule(
    scene: &Scene,
    e: &Evaluation,
    p: Parameter,
    noise: Option<&optics::NoiseShape>,
) -> Result<(f64, f64), Error> {
    let not_smooth = |reason: String| Error::NotDifferentiable { parameter: p.describe(), reason };
    let lens = scene.lens();
    let field = scene.field();
    let f_number = lens.f_number();
    let family = lens.describe();
    let refused = || {
        not_smooth(format!(
            "lens.design_wavelength_nm: {family}: the design wavelength's gradient is computed for a lens whose \
             every order is the full circular pupil with a defocus alone and that gives how its orders move with λ0 \
             (the chromatic, refractive and harmonic families without Seidel terms), on axis or where the field \
             leaves the OTF as on axis, off axis with the lateral colour f0 tan θ (λ0/λ − 1) on the exact 1-D \
             engine over a band or under a line (each order its own), and through a decentred circular iris there \
             (its tilt moving with W020); it is 0 for a phase lens with a geometric phase (its radian profile does \
             not depend on λ0); this scene's orders are not that here (off axis: a centred iris smaller than the \
             aperture, an iris on the FFT path, or Seidel terms, which the exact engine's lane does not carry; a \
             phase lens's refractive profile scales its path per radian with λ0 and a diffractive one its orders' efficiencies, and a phase map's geometric \
             phase its reference sphere by 1 − λ/λ0: not followed yet)"
        ))
    };
    // off axis first: the reason that holds whatever the camera
    if !field.is_on_axis() {
        return Err(refused());
    }
    let camera = scene.camera();
    if camera.pixel_mtf() && noise.is_none() {
        return Err(not_smooth(
            "lens.design_wavelength_nm: with camera.pixel_mtf = true the design wavelength's gradient is computed on \
             the value's own rule (the closed form, a line, the per-frequency product rule), which this scene's \
             engine is not (the reference panels rule: a wavelength's cutoff inside the band or \
             options.spectral_rule = \"panels\"; set camera.pixel_mtf = false)"
                .to_owned(),
        ));
    }
    // each spectral node: (λ, ρ(λ) × the rule's weight, [(τ_o, w_o, δw_o, δτ_o)] per order)
    type Node = (f64, f64, Vec<[f64; 4]>);
    let node = |lambda: f64, weight: f64| -> Result<Node, Error> {
        let orders = lens.orders(lambda, field);
        let rates = lens.design_wavelength_rates(lambda, field).ok_or_else(refused)?;
        if rates.len() != orders.len() {
            return Err(refused());
        }
        let mut out = Vec::with_capacity(orders.len());
        for (o, [d_w020, d_tau]) in orders.iter().zip(rates) {
            let w = &o.wavefront;
            let plain = matches!(o.pupil, optics::Pupil::Full)
                && w.image_shift_m == [0.0, 0.0]
                && [w.spherical_m, w.coma_m, w.astigmatism_m, w.field_curvature_m] == [0.0; 4];
            if !plain {
                return Err(refused());
            }
            out.push([o.efficiency, w.defocus_m / lambda, d_w020 / lambda, d_tau]);
        }
        Ok((lambda, weight, out))
    };
    let value = |nodes: &[Node], nu: f64| -> f64 {
        let (mut total, mut o) = (0.0, 0.0);
        for (lambda, weight, orders) in nodes {
            for &[tau, w, _, _] in orders {
                total += weight * tau;
                o += weight * tau * optics::defocus_otf(nu * lambda * f_number, w);
            }
        }
        o / total
    };
    let at = |nodes: &[Node], nu: f64| -> (f64, f64) {
        let (mut total, mut o, mut d, mut moved) = (0.0, 0.0, 0.0, 0.0);
        for (lambda, weight, orders) in nodes {
            let s = nu * lambda * f_number;
            for &[tau, w, d_w, d_tau] in orders {
                let h = optics::defocus_otf(s, w);
                // ∂H/∂w = (w ∂H/∂w)/w, 0 at w = 0 (H even in w)
                let slope = if w == 0.0 { 0.0 } else { optics::defocus_otf_log_derivative(s, w) / w };
                total += weight * tau;
                moved += weight * d_tau;
                o += weight * tau * h;
                d += weight * (tau * slope * d_w + d_tau * h);
            }
        }
        let o = o / total;
        // under a noise spectrum each frequency's weight divided by n(ν)
        (o, (d / total - o * moved / total) / noise.map_or(1.0, |n| n.value(nu)))
    };
    let refinement = Refinement { lambda_panels: (2, 256), nu_panels: 1024, zero_width: &|_| 1e-13 * camera.nyquist() };
    // the pixel MTF on the weighted pass's weights (the white pass refuses it above)
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    let (nodes, d_mtf) = reference_rule(scene, e, p, refinement, pixel, node, value, at)?;
    let (mut total, mut moved) = (0.0, 0.0);
    for (_, weight, orders) in &nodes {
        for &[tau, _, _, d_tau] in orders {
            total += weight * tau;
            moved += weight * d_tau;
        }
    }
    Ok((moved / total, d_mtf))
}

/// How [`reference_rule`] refines: its first and last number of λ panels a piece, its last
/// number of ν panels, and the width (of the bracket's upper end) to which it brackets the
/// OTF's zeros.
struct Refinement<'a> {
    lambda_panels: (usize, usize),
    nu_panels: usize,
    zero_width: &'a dyn Fn(f64) -> f64,
}

/// The slow reference rule of a mean-MTF derivative, shared by the F-number's `D_K`
/// ([`aperture_partials_by_own_rule`]) and the library bias's `∂M̄`
/// ([`library_bias_partials`]): composite 16-point Gauss–Legendre rules in λ over the detected
/// spectrum's support (a Gaussian factor's tails cut at 9σ; a line's single node), split at its
/// and the lens's breakpoints, each node built by `node(λ, ρ(λ) × the rule's weight)`; and
/// `(1/ν_N) ∫ P(ν) sign(O) ∂O dν` on Gauss–Legendre panels in ν split at the sign changes of
/// `value` (the kink of |O|; `P` the pixel MTF where `pixel` is its pitch), `at` giving
/// `(O, ∂O)`. The λ panels are doubled on 8 ν panels, then the ν panels on those λ nodes, each
/// until the integral moves by at most the tolerance times `max(|integral|, M̄)` or reaches
/// its `refinement` limit. Returns the λ nodes and the integral.
#[allow(clippy::too_many_arguments)]
fn reference_rule<N>(
    scene: &Scene,
    e: &Evaluation,
    p: Parameter,
    refinement: Refinement,
    pixel: Option<f64>,
    node: impl Fn(f64, f64) -> Result<N, Error>,
    value: impl Fn(&[N], f64) -> f64,
    at: impl Fn(&[N], f64) -> (f64, f64),
) -> Result<(Vec<N>, f64), Error> {
    let detected = crate::evaluate::detected_spectrum(scene);
    let nyquist = e.nyquist_cyc_per_mm * 1e3;
    let tolerance = scene.options().settings().tolerance;
    let line = detected.as_line();
    // the spectral interval and its breakpoints
    let (lo, hi) = match line {
        Some(_) => (0.0, 0.0),
        None => {
            let (mut lo, mut hi) = detected.support();
            for g in detected.gaussians() {
                lo = lo.max(g.center() - 9.0 * g.sigma());
                hi = hi.min(g.center() + 9.0 * g.sigma());
            }
            if !(hi.is_finite() && hi > lo) {
                return Err(Error::NotDifferentiable {
                    parameter: p.describe(),
                    reason: "the detected spectrum has no bounded support (a Gaussian factor, a table or a band) to \
                             integrate over"
                        .to_owned(),
                });
            }
            (lo, hi)
        }
    };
    let mut ends: Vec<f64> = vec![lo];
    ends.extend(detected.breakpoints().into_iter().chain(scene.lens().breakpoints()).filter(|&x| x > lo && x < hi));
    ends.push(hi);
    ends.sort_by(f64::total_cmp);
    ends.dedup();
    let spectral_rule = |panels: usize| -> Result<Vec<N>, Error> {
        if let Some(line) = &line {
            return Ok(vec![node(line.wavelength_m, line.weight)?]);
        }
        let mut nodes = Vec::new();
        for w in ends.windows(2) {
            let h = (w[1] - w[0]) / panels as f64;
            for i in 0..panels {
                let centre = w[0] + h * (i as f64 + 0.5);
                for &(x, wx) in optics::quad::rule() {
                    let lambda = centre + 0.5 * h * x;
                    let rho = detected.value(lambda);
                    if rho != 0.0 {
                        nodes.push(node(lambda, 0.5 * h * wx * rho)?);
                    }
                }
            }
        }
        Ok(nodes)
    };
    let integrate = |nodes: &[N], panels: usize| -> f64 {
        let value = |nu| value(nodes, nu);
        let at = |nu| {
            let (o, d) = at(nodes, nu);
            (o, [d])
        };
        let [sum] = sign_split_integral(nyquist, panels, value, at, refinement.zero_width, pixel);
        sum
    };
    let converged = |change: f64, next: f64| change <= tolerance * next.abs().max(e.mean_mtf);
    let nu_coarse = 8;
    let (first, most) = refinement.lambda_panels;
    let mut lambda_panels = first;
    let mut nodes = spectral_rule(lambda_panels)?;
    let mut previous = integrate(&nodes, nu_coarse);
    while line.is_none() {
        lambda_panels *= 2;
        let finer = spectral_rule(lambda_panels)?;
        let next = integrate(&finer, nu_coarse);
        let change = (next - previous).abs();
        (nodes, previous) = (finer, next);
        if converged(change, next) || lambda_panels >= most {
            break;
        }
    }
    let mut nu_panels = nu_coarse;
    let integral = loop {
        nu_panels *= 2;
        let next = integrate(&nodes, nu_panels);
        let change = (next - previous).abs();
        previous = next;
        if converged(change, next) || nu_panels >= refinement.nu_panels {
            break next;
        }
    };
    Ok((nodes, integral))
}

/// The ends of `panels` equal panels over `[0, nyquist]` with the sign changes of `otf` between
/// them added (each found by bisection until the bracket `[lo, hi]` is at most `width(hi)` wide:
/// 1e-15 of its frequency for the spectral keys' rules, 1e-13 of `nyquist` for the F-number's
/// reference rule), so that a Gauss rule on each piece meets the kink of |O| at a zero only at
/// its ends.
fn sign_change_ends(nyquist: f64, panels: usize, otf: impl Fn(f64) -> f64, width: impl Fn(f64) -> f64) -> Vec<f64> {
    let mut ends = vec![0.0];
    let h = nyquist / panels as f64;
    let mut previous = (0.0, 1.0);
    for i in 1..=panels {
        let nu = if i == panels { nyquist } else { i as f64 * h };
        let value = otf(nu);
        if value * previous.1 < 0.0 {
            let (mut lo, mut hi, f_lo) = (previous.0, nu, previous.1);
            while hi - lo > width(hi) {
                let m = 0.5 * (lo + hi);
                if otf(m) * f_lo > 0.0 {
                    lo = m;
                } else {
                    hi = m;
                }
            }
            ends.push(0.5 * (lo + hi));
        }
        ends.push(nu);
        previous = (nu, value);
    }
    ends
}

/// `(∂M̄/∂b, ∂ln N/∂b, ∂ln N_T/∂b)` ([`library_bias_mean_mtf_partials`]).
pub type BiasTriple = (f64, f64, f64);

/// `(∂M̄/∂b, ∂ln N/∂b, ∂ln N_T/∂b)` of a library lens's bias of parameter `index`
/// (docs/physics.md, "Gradients: a library's parameter bias"): with `reference`, by the slow
/// reference rule (`library_bias_partials`: its own Gauss–Legendre panels in λ and ν); else on
/// the value's own rules (the lanes beside the evaluation's OTF values), `None` where the
/// value's engine gives no lanes. The evaluation of `scene` is returned beside them (the same,
/// bit for bit, either way). For the tests that hold the one against the other.
pub fn library_bias_mean_mtf_partials(
    scene: &Scene,
    index: usize,
    reference: bool,
) -> Result<(Evaluation, Option<BiasTriple>), Error> {
    let bias = if reference { Vec::new() } else { vec![index] };
    let (e, _, _, lanes) = evaluate_field_differentiated(scene, false, &[], &bias)?;
    let found = if reference {
        let b = library_bias_partials(scene, &e, Parameter::LibraryBias(index), index)?;
        Some((b.mean_mtf, b.ln_photoelectrons, b.ln_transmitted))
    } else {
        lanes.map(|l| (l.mean_mtf[0], l.ln_photoelectrons[0], l.ln_transmitted[0]))
    };
    Ok((e, found))
}

/// What a library lens's parameter bias moves ([`library_bias_partials`]).
struct BiasPartials {
    /// `∂ln N/∂b = ∫ρ Σ_o ∂τ_o dλ / ∫ρ Σ_o τ_o dλ`
    ln_photoelectrons: f64,
    /// `∂ln N_T/∂b = ∫ρ ∂T dλ / ∫ρ T dλ`
    ln_transmitted: f64,
    /// `∂M̄/∂b`
    mean_mtf: f64,
}

/// One spectral node of [`library_bias_partials`]: its rule weight times `ρ(λ)`, `T`, `∂T` and
/// per order `(τ_o, ∂τ_o, the order on the radial engine, ∂A, ∂W)`.
struct BiasNode {
    lambda: f64,
    weight: f64,
    transmission: (f64, f64),
    orders: Vec<BiasOrder>,
}

type BiasOrder = (f64, f64, optics::radial::RadialOrder, optics::radial::RadialProfile, optics::radial::RadialProfile);

/// The derivatives of `ln N`, `ln N_T` and the mean MTF with respect to the bias of a library
/// lens's parameter `index` (docs/physics.md, "Gradients: a library's parameter bias"). Each
/// wavelength's orders move by [`optics::LensModel::order_derivatives`] (forward mode on the
/// lens's own rule: the cubic rows' `∂t/∂p`, the zones' `c_1`, the fits); the polychromatic OTF
/// `O = ∫ρ Σ τ_o H_o dλ / ∫ρ Σ τ_o dλ` then moves by
///
/// ```text
/// ∂O = [∫ρ Σ_o (∂τ_o H_o + τ_o ∂H_o) dλ − O ∫ρ Σ_o ∂τ_o dλ] / ∫ρ Σ_o τ_o dλ
/// ```
///
/// with `∂H_o` the radial engine's amplitude and phase lane on the value's rule
/// ([`optics::radial::RadialOrder::otf_and_field_derivative`]), and
/// `∂M̄ = (1/ν_N) ∫ P(ν) sign(O) ∂O dν` (`P` the pixel MTF where the camera applies it).
///
/// The slow reference: where the value's engine carries the lanes, the gradient takes them from
/// the evaluation's own pass instead ([`crate::evaluate::BiasLanes`],
/// [`optics::Polychromatic::mean_mtf_and_field_gradient`]); this rule is taken where it does
/// not, and by the tests ([`library_bias_mean_mtf_partials`]). The
/// integrals are this function's own composite 16-point Gauss–Legendre rules, as
/// [`aperture_partials_by_own_rule`]'s: in λ over the detected spectrum's support (a Gaussian's
/// tails cut at 9σ), split at its and the lens's breakpoints (the library's wavelengths, where
/// its rows are linear in λ), doubled on 8 ν panels until `∂M̄` moves by at most the tolerance
/// times `max(|∂M̄|, M̄)`; then the ν rule (panels split at the sign changes of `O`, the kink
/// of |O|) doubled the same way. Each OTF and its lane to a tenth of the tolerance.
fn library_bias_partials(scene: &Scene, e: &Evaluation, p: Parameter, index: usize) -> Result<BiasPartials, Error> {
    library_bias_partials_over(scene, e, p, index, None)
}

/// [`library_bias_partials`] with each frequency's weight of `∂O` divided by `n(ν)` where
/// `noise` is given: its `mean_mtf` is then `∂G`'s (docs/physics.md, "Gradients under a noise
/// spectrum"; the table's kinks integrated across as the ν panels double).
fn library_bias_partials_over(
    scene: &Scene,
    e: &Evaluation,
    p: Parameter,
    index: usize,
    noise: Option<&optics::NoiseShape>,
) -> Result<BiasPartials, Error> {
    let not_smooth = |reason: String| Error::NotDifferentiable { parameter: p.describe(), reason };
    let camera = scene.camera();
    let lens = scene.lens();
    let field = scene.field();
    if !field.is_on_axis() || e.numerics.engine.starts_with("fft") {
        // the radial pupil seen by the oblique wave, or a 2-D layout's site map, on the FFT path
        return library_fft::library_bias_on_fft_path(scene, e, p, index, noise);
    }
    let f_number = lens.f_number();
    let tolerance = scene.options().settings().tolerance;
    let accuracy = 0.1 * tolerance;
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    let node = |lambda: f64, weight: f64| -> Result<BiasNode, Error> {
        let orders = lens.orders(lambda, field);
        let Some(d) = lens.order_derivatives(lambda, index) else {
            return Err(not_smooth(format!(
                "the lens gives no derivative of its orders in this parameter at {:.3} nm (a library lens with \
                 a radial layout and lens.library_interpolation = \"cubic\", a bias index below its number of \
                 parameters, the lens's own pupil mapping, and an imaging order with |c_1| > 0 at every radius)",
                lambda * 1e9
            )));
        };
        if d.fields.len() != orders.len() || d.efficiencies.len() != orders.len() {
            return Err(not_smooth("the lens's order derivatives do not match its orders".to_owned()));
        }
        let mut out = Vec::with_capacity(orders.len());
        for ((o, &d_tau), (d_amplitude, d_wavefront)) in orders.iter().zip(&d.efficiencies).zip(d.fields) {
            let w = &o.wavefront;
            let optics::Pupil::Radial(pupil) = &o.pupil else {
                return Err(not_smooth("an order's pupil is not a radial pupil".to_owned()));
            };
            if !pupil.is_symmetric()
                || w.image_shift_m != [0.0, 0.0]
                || [w.spherical_m, w.coma_m, w.astigmatism_m, w.field_curvature_m] != [0.0; 4]
            {
                return Err(not_smooth(
                    "an order is not a rotationally symmetric radial pupil on axis (Zernike or Seidel terms, an \
                     image shift)"
                        .to_owned(),
                ));
            }
            let radial = optics::radial::RadialOrder::new(pupil.clone(), w.defocus_m, lambda)
                .with_table_rule(scene.options().table_rule);
            out.push((o.efficiency, d_tau, radial, d_amplitude, d_wavefront));
        }
        Ok(BiasNode { lambda, weight, transmission: (lens.transmission(lambda), d.transmission), orders: out })
    };
    // ∫ρ Σ τ_o and ∫ρ Σ ∂τ_o over the nodes
    let sums = |nodes: &[BiasNode]| -> (f64, f64) {
        nodes.iter().fold((0.0, 0.0), |(s, d), n| {
            let (tau, d_tau) = n.orders.iter().fold((0.0, 0.0), |(a, b), o| (a + o.0, b + o.1));
            (s + n.weight * tau, d + n.weight * d_tau)
        })
    };
    let value = |nodes: &[BiasNode], nu: f64| -> f64 {
        let mut o = 0.0;
        for n in nodes {
            for (tau, _, radial, _, _) in &n.orders {
                o += n.weight * tau * radial.otf(nu * n.lambda * f_number, accuracy);
            }
        }
        o / sums(nodes).0
    };
    // (O, ∂O) at ν
    let at = |nodes: &[BiasNode], nu: f64| -> (f64, f64) {
        let (total, d_total) = sums(nodes);
        let (mut o, mut d) = (0.0, 0.0);
        for n in nodes {
            for (tau, d_tau, radial, d_amplitude, d_wavefront) in &n.orders {
                let (h, d_h) =
                    radial.otf_and_field_derivative(nu * n.lambda * f_number, accuracy, d_amplitude, d_wavefront);
                o += n.weight * tau * h;
                d += n.weight * (d_tau * h + tau * d_h);
            }
        }
        let o = o / total;
        (o, (d - o * d_total) / total / noise.map_or(1.0, |n| n.value(nu)))
    };
    let refinement = Refinement { lambda_panels: (1, 64), nu_panels: 512, zero_width: &|hi| 1e-15 * hi };
    let (nodes, mean_mtf) = reference_rule(scene, e, p, refinement, pixel, node, value, at)?;
    let (total, d_total) = sums(&nodes);
    let (t, d_t) =
        nodes.iter().fold((0.0, 0.0), |(a, b), n| (a + n.weight * n.transmission.0, b + n.weight * n.transmission.1));
    Ok(BiasPartials { ln_photoelectrons: d_total / total, ln_transmitted: d_t / t, mean_mtf })
}

/// Whether there are orders and every one is the full circle or a circular iris, with a defocus
/// alone: the exact 1-D engine's lanes over azimuth (lateral colour, an iris's decentre).
fn circular_defocus_orders(orders: &[optics::Order]) -> bool {
    !orders.is_empty()
        && orders.iter().all(|o| {
            let circle = match &o.pupil {
                optics::Pupil::Full => true,
                optics::Pupil::Aperture(a) => a.as_circle().is_some(),
                _ => false,
            };
            circle && o.wavefront.is_defocus_only()
        })
}

/// The ends of the pieces `[0, ν_N]` is cut into for a noise-weighted mean: the noise table's
/// rows inside it (where `1/n` has its kinks), none without a noise spectrum.
fn noise_row_ends(noise: Option<&optics::NoiseShape>, nyquist: f64) -> Vec<f64> {
    let mut ends = vec![0.0];
    if let Some(n) = noise {
        ends.extend(n.rows().iter().copied().filter(|&r| r > 0.0 && r < nyquist));
    }
    ends.push(nyquist);
    ends
}
