//! The edges of a lens's design band (a dispersion-engineered lens's `lens.design_band_nm`):
//! limits of the signal's integrals over λ (docs/physics.md, "Gradients: the
//! dispersion-engineered lens").

use crate::{Error, Scene};

use std::cell::{OnceCell, RefCell};
use std::collections::HashMap;

use super::{
    DirectionalRule, Parameter, modulus_derivative, noise_row_ends, on_value_engine, product_rule_on_axis,
    sign_split_mean,
};

/// `(∂ln N/∂x, ∂M̄/∂x)` (per m) for the edge `x` of the lens's design band
/// ([`optics::LensModel::design_band`]; `edge` 0 its short end λ_min, 1 its long end λ_max),
/// outside which every order's efficiency is 0 and the transmitted light is background alone.
/// The signal's integrals run over the band: with `D = ∫_{λ_min}^{λ_max} ρ Σ_o τ_o dλ` the
/// detected weight and `T_x = ρ(x) Σ_o τ_o(x)` its density at the edge (the orders' efficiency
/// there, the band's own), Leibniz's rule gives
/// - `∂ln N/∂λ_max = T_x/D`, `∂ln N/∂λ_min = −T_x/D`;
/// - the normalized OTF `O = ∫ ρ Σ_o τ_o H_o dλ / D` moves as `±(T_x/D)(O_x − O)`, `O_x` the OTF
///   at the single wavelength `x`, so `∂M̄/∂x = ±(T_x/D)((1/ν_N) ∫ P sign(O) O_x dν − M̄)`;
/// - where the OTF depends on direction, `∂|O| = ±(T_x/D)(Re(O* O_x)/|O| − |O|)` on the value's
///   rule over directions.
///
/// As a top-hat spectrum's edges are (`top_hat_partials`, docs/physics.md "Gradients: a top-hat's
/// edges"), with the lens's window in place of the spectrum's: the total transmission `T` does
/// not move (the caller's `∂B = −∂N` with the stray light). The integrals in ν on 16-point
/// Gauss–Legendre panels split at the sign changes of `O`, doubled until they move by at most the
/// tolerance times `M̄`; `M̄` on the same rule; the band's OTF and both means again at
/// `max(q, 1e-4)` times the tolerance where `I_x − M̄` is `q < 1` of `M̄`. Under a noise spectrum (`noise`) each frequency's weight divided by
/// `n(ν)`, `M̄` the weighted mean on the same rule. The band's OTF is computed once per
/// frequency (the sign and the lane read the same value). Where the value's engine is the
/// per-frequency product rule on axis (no noise spectrum), the lane rides on that engine's own
/// pass instead, the band's window on the spectrum ([`band_edge_on_value_rule`]).
/// `O_x` is a line's, or on the overlap engine its slivers' extrapolated ([`EdgeOtf`]). Refused
/// where the lens has no design band.
pub(super) fn band_edge_partials(
    scene: &Scene,
    e: &crate::Evaluation,
    p: Parameter,
    edge: usize,
    noise: Option<&optics::NoiseShape>,
    pass: &EdgePass,
) -> Result<(f64, f64), Error> {
    let lens = scene.lens();
    let Some((lo, hi)) = lens.design_band() else {
        return Err(Error::NotDifferentiable {
            parameter: p.describe(),
            reason: format!("{}: the lens has no design band", lens.describe()),
        });
    };
    let (x, sign) = if edge == 0 { (lo, -1.0) } else { (hi, 1.0) };
    let field = scene.field();
    let detected = crate::evaluate::detected_spectrum(scene);
    let nyquist = e.nyquist_cyc_per_mm * 1e3;
    let settings = scene.options().settings();
    let camera = scene.camera();
    let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
    let over_noise = |nu: f64| noise.map_or(1.0, |n| 1.0 / n.value(nu));
    // T_x/D: the detected density times the orders' efficiency at the edge, over the weight
    let efficiency: f64 = lens.orders(x, field).iter().map(|o| o.efficiency).sum();
    if detected.value(x) * efficiency == 0.0 {
        // no detected light at the edge: neither N nor the OTF's weights move
        return Ok((0.0, 0.0));
    }
    if noise.is_none()
        && let Some(found) = pass.lanes(scene, e)
    {
        return Ok(found.edges[edge]);
    }
    // the edge's single wavelength (a line of any weight: its OTF is normalized); beside it the
    // band's first (last) δ and 2δ inside the band (`edge_otf`)
    let line = radiometry::Spectrum::Line(radiometry::Line::new(x, 1e-9, 1.0)?);
    let inside = |width: f64| -> Result<radiometry::Spectrum, Error> {
        let (a, b) = if edge == 0 { (x, x + width) } else { (x - width, x) };
        Ok(radiometry::Spectrum::TopHat(radiometry::TopHat::new(a, b, 1.0)?))
    };
    let slivers = [inside(EDGE_SLIVER_M)?, inside(2.0 * EDGE_SLIVER_M)?];
    // (T_x/D, I_x, M̄) with the band's OTF and both means held to `tolerance` relative to M̄
    let means = |tolerance: f64| -> Result<(f64, f64, f64), Error> {
        let settings = optics::Settings { tolerance, ..settings };
        let whole = optics::Polychromatic::with_settings(lens, &detected, field, nyquist, None, settings)?;
        let at_x = EdgeOtf::of(lens, &whole, &line, &slivers, field, nyquist, settings)?;
        let density = detected.value(x) * efficiency / whole.total_weight();
        if whole.direction_dependent() || at_x.direction_dependent() {
            let rule = DirectionalRule::of(scene, &whole, tolerance);
            let [j, i_x, _] = rule.mean_split(&noise_row_ends(noise, nyquist), [1.0; 3], &|nu, azimuth| {
                let o = whole.otf_along(nu, azimuth);
                let pix = pixel.map_or(1.0, |p| optics::pixel_mtf(p, nu)) * over_noise(nu);
                let o_x = at_x.otf_along(nu, azimuth);
                [pix * o.norm(), pix * modulus_derivative([o.re, o.im], o_x), 0.0]
            });
            return Ok((density, i_x, j));
        }
        // the band's OTF once per frequency: the sign changes' search, the sign and the lane
        // read the same values
        let known: RefCell<HashMap<u64, f64>> = RefCell::new(HashMap::new());
        let band_otf = |nu: f64| -> f64 {
            if let Some(&o) = known.borrow().get(&nu.to_bits()) {
                return o;
            }
            let o = whole.otf(nu);
            known.borrow_mut().insert(nu.to_bits(), o);
            o
        };
        let [i_x, j] = sign_split_mean(
            nyquist,
            8,
            band_otf,
            |nu| {
                let pix = pixel.map_or(1.0, |p| optics::pixel_mtf(p, nu)) * over_noise(nu);
                let o = band_otf(nu);
                (o, [pix * at_x.otf(nu), pix * o])
            },
            |change, next| change[0].abs().max(change[1].abs()) <= tolerance * next[1].abs(),
        );
        Ok((density, i_x, j))
    };
    // I_x − M̄ is a difference of two means each held to the tolerance relative to M̄: where it
    // is q = |I_x − M̄|/M̄ < 1 of M̄, both again at max(q, 1e-4) times the tolerance, so that the
    // difference keeps the tolerance relative to itself (as the field angles' lanes do)
    let (mut density, mut i_x, mut j) = means(settings.tolerance)?;
    let q = (i_x - j).abs() / j.abs().max(f64::MIN_POSITIVE);
    if q < 1.0 {
        (density, i_x, j) = means(settings.tolerance * q.max(1e-4))?;
    }
    // M̄ on the same rule as I_x (white, or the weighted G under a noise spectrum)
    Ok((sign * density, sign * density * (i_x - j)))
}

/// The width δ (m) of the band's sliver at an edge whose OTF stands for the edge's single
/// wavelength's on the overlap engine ([`EdgeOtf`]): `2 O_δ − O_2δ` leaves `O(δ² O″)`, below
/// 1e-10 of the OTF for `O″` of a few 1e-3 per nm² (the reduced achromat's defocus).
const EDGE_SLIVER_M: f64 = 1e-13;

/// The OTF at a band edge's single wavelength `x` for [`band_edge_partials`]: the line's engine,
/// or, where the band's own engine is the overlap quadrature (Zernike or Seidel terms over the
/// full circle), the same engine over the band's slivers `[x, x + δ]` and `[x, x + 2δ]` (inside
/// the band: `[x − 2δ, x]` at the long edge) extrapolated to zero width, `O_x = 2 O_δ − O_2δ`
/// (a sliver of width `w` at the short edge has the OTF `O_x + O′w/2 + O(w²)`): a line with those terms is on the
/// FFT grids, whose pupil sampling leaves its OTF about 5e-5 off the band's quadrature (the
/// reduced achromat with Z4 0.02 µm and Z8 0.01 µm at 795 nm: 0.696469 against 0.696501), an
/// error the difference `I_x − M̄` of the edge's lane would carry (docs/physics.md,
/// "Gradients: the dispersion-engineered lens").
struct EdgeOtf<'a>(Vec<(f64, optics::Polychromatic<'a>)>);

impl<'a> EdgeOtf<'a> {
    /// The edge's engines at `settings`, beside the band's engine `whole`.
    #[allow(clippy::too_many_arguments)]
    fn of(
        lens: &'a dyn optics::LensModel,
        whole: &optics::Polychromatic<'_>,
        line: &'a radiometry::Spectrum,
        slivers: &'a [radiometry::Spectrum; 2],
        field: optics::Field,
        nyquist: f64,
        settings: optics::Settings,
    ) -> Result<EdgeOtf<'a>, Error> {
        let engine =
            |s: &'a radiometry::Spectrum| optics::Polychromatic::with_settings(lens, s, field, nyquist, None, settings);
        if matches!(whole.engine(), optics::Engine::Overlap { .. }) {
            let [narrow, wide] = [engine(&slivers[0])?, engine(&slivers[1])?];
            if [&narrow, &wide].iter().all(|p| matches!(p.engine(), optics::Engine::Overlap { .. })) {
                return Ok(EdgeOtf(vec![(2.0, narrow), (-1.0, wide)]));
            }
        }
        Ok(EdgeOtf(vec![(1.0, engine(line)?)]))
    }

    /// Whether some engine's OTF depends on direction.
    fn direction_dependent(&self) -> bool {
        self.0.iter().any(|(_, p)| p.direction_dependent())
    }

    /// The (real) OTF where it does not depend on direction.
    fn otf(&self, nu: f64) -> f64 {
        self.0.iter().map(|(c, p)| c * p.otf(nu)).sum()
    }

    /// `[Re, Im]` of the OTF along `azimuth`.
    fn otf_along(&self, nu: f64, azimuth: f64) -> [f64; 2] {
        self.0.iter().fold([0.0; 2], |[re, im], (c, p)| {
            let o = p.otf_along(nu, azimuth);
            [re + c * o.re, im + c * o.im]
        })
    }
}

/// Both edges' `(∂ln N/∂x, ∂M̄/∂x)` of one point's gradient (and, on the per-frequency product
/// rule, the design wavelength's `(∂ln N/∂ln λ0, ∂M̄/∂ln λ0)`), from one pass of the value's
/// engine ([`band_edges_on_value_rule`], [`band_edges_on_value_pass`]), made when the first of
/// them is asked and read by the others.
#[derive(Debug, Default)]
pub(super) struct EdgePass(OnceCell<Option<EdgeLanes>>);

/// What [`EdgePass`] keeps.
#[derive(Clone, Copy, Debug)]
pub(super) struct EdgeLanes {
    /// `(∂ln N/∂x, ∂M̄/∂x)` at the band's short and long edges (per m)
    edges: [(f64, f64); 2],
    /// `(∂ln N/∂ln λ0, ∂M̄/∂ln λ0)` where the pass gave it
    design: Option<(f64, f64)>,
    /// `(∂M̄/∂ln F#, ∂M̄/∂ln f0)` at fixed β where the pass gave the defocus lane
    aperture: Option<(f64, f64)>,
}

impl EdgePass {
    /// The pass's lanes for the scene's lens's design band (white noise), made on the first call;
    /// `None` where the lens has no band or the value's engine gives no such pass.
    fn lanes(&self, scene: &Scene, e: &crate::Evaluation) -> Option<EdgeLanes> {
        *self.0.get_or_init(|| {
            let band = scene.lens().design_band()?;
            let detected = crate::evaluate::detected_spectrum(scene);
            band_edges_on_value_rule(scene, e, &detected, band)
                .or_else(|| band_edges_on_value_pass(scene, &detected, band))
        })
    }
}

/// `(∂ln N/∂ln λ0, ∂M̄/∂ln λ0)` of a lens with a design band from the band edges' pass, where it
/// gave it (the per-frequency product rule on axis: the design wavelength's lane on the same
/// climb as the edges', [`band_edges_on_value_rule`]); `None` elsewhere (the caller's rule).
pub(super) fn design_wavelength_on_edge_pass(
    scene: &Scene,
    e: &crate::Evaluation,
    pass: &EdgePass,
) -> Option<(f64, f64)> {
    pass.lanes(scene, e)?.design
}

/// `(∂M̄/∂ln F#, ∂M̄/∂ln f0)` of a lens with a design band (white noise) from the band edges'
/// pass where it gave them (the per-frequency product rule on axis: the defocus lane `D_K` on the
/// same climb as the edges' and the design wavelength's, [`band_edges_on_value_rule`]), so that
/// the F-number and focal length take no pass of their own; where no order has a wavefront error
/// (a true achromat) the pass-free [`aperture_without_defocus`] first. `None` elsewhere, or where
/// the value's own pass gave the lane (`pass_found`): the caller's rules.
pub(super) fn aperture_on_edge_pass(
    scene: &Scene,
    e: &crate::Evaluation,
    p: Parameter,
    pass: &EdgePass,
    pass_found: bool,
) -> Result<Option<(f64, f64)>, Error> {
    if pass_found || scene.lens().design_band().is_none() {
        return Ok(None);
    }
    if let Some(found) = aperture_without_defocus(scene, e, p)? {
        return Ok(Some(found));
    }
    Ok(pass.lanes(scene, e).and_then(|l| l.aperture))
}

/// `±T_x/D` at both edges `x` of the band `(lo, hi)` (`-` at `lo`), with `D` the engine's total
/// weight: the detected density times the orders' efficiency at the edge, over the weight.
fn edge_densities(scene: &Scene, detected: &radiometry::Spectrum, (lo, hi): (f64, f64), total: f64) -> [f64; 2] {
    let density = |x: f64| {
        let efficiency: f64 = scene.lens().orders(x, scene.field()).iter().map(|o| o.efficiency).sum();
        detected.value(x) * efficiency / total
    };
    [-density(lo), density(hi)]
}

/// [`band_edge_partials`] on the value's own engine, where it is the per-frequency product rule on
/// axis, built for the detected spectrum with the band's window on it (the same integrand, the
/// orders' efficiency being 0 outside the band), so that its spectral panels end at the design
/// band's edges (docs/physics.md, "Gradients: the dispersion-engineered lens"): as a top-hat's
/// edges on the value's rule
/// (`top_hat_on_value_rule`), the Chebyshev–Lobatto points of every spectral level include the
/// panels' ends, so the value's own sums there give the edge's OTF `O_x` (times the detected
/// density and the orders' efficiency), and each OTF value carries `±(T_x/D)(O_x − O)` beside it
/// ([`optics::Polychromatic::mean_mtf_and_spectral_lanes`] with its edge lanes), integrated with
/// the frequency rule's accepted weights: the lane held to the value's own error control. `∂ln N
/// = ±T_x/D` as there. Both edges from the one pass. `None` on the other engines, off axis, or
/// where the engine's ends are not the band's (a Gaussian's ±7σ inside the band): the caller's
/// rule.
fn band_edges_on_value_rule(
    scene: &Scene,
    e: &crate::Evaluation,
    detected: &radiometry::Spectrum,
    (lo, hi): (f64, f64),
) -> Option<EdgeLanes> {
    if !product_rule_on_axis(scene, e) {
        return None;
    }
    // the detected spectrum with the band's window on it: the same integrand (the orders'
    // efficiency is 0 outside the band), its support the band, so the engine's spectral panels
    // end at the band's edges
    let window = radiometry::Spectrum::TopHat(radiometry::TopHat::new(lo, hi, 1.0).ok()?);
    let windowed = radiometry::Spectrum::product(vec![detected.clone(), window]);
    on_value_engine(scene, &windowed, scene.options().settings(), |poly| {
        let (a, b) = poly.spectral_ends()?;
        if (a - lo).abs() > 1e-12 * lo || (b - hi).abs() > 1e-12 * hi {
            return None;
        }
        let found = poly.mean_mtf_and_design_and_edge_lanes()?;
        if poly.over_budget().is_some() {
            return None;
        }
        let [design, d_a, d_b] = found.design_and_edges;
        let [n_a, n_b] = edge_densities(scene, &windowed, (a, b), poly.total_weight());
        let design = poly.design_signal_rate().map(|rate| (rate, design));
        // the F-number's and focal length's lanes on the same pass (`defocus_on_value_rule`'s
        // forms): by parts `∂M̄/∂ln F# = P(ν_N)|O(ν_N)| − M̄ − P_ν − 2 D_K`, `∂M̄/∂ln f0 = D_K`,
        // the end term and the mean this engine's own
        let camera = scene.camera();
        let pixel = camera.pixel_mtf().then_some(camera.pixel_pitch());
        let edge = crate::evaluate::nyquist_edge(poly, camera.nyquist(), pixel);
        let d_k = found.defocus;
        let aperture = Some((edge - found.mean - found.pixel_slope - 2.0 * d_k, d_k));
        Some(EdgeLanes { edges: [(n_a, d_a), (n_b, d_b)], design, aperture })
    })
}

/// [`band_edge_partials`] on the value's own pass where its engine reads the OTF per frequency on
/// the adaptive rule without a product rule's edge lanes (the reference panels rule: a
/// wavelength's cutoff `1/(λF#)` inside `[0, ν_N]`, the `D = 0.2 mm` design at F/16.8), on axis
/// or where the field leaves the OTF as on axis, and the OTF the same along every direction:
/// beside each OTF value `O(ν)` the value reads, the edges' single-wavelength OTFs `O_x(ν)`
/// (each edge's orders, one line's engine each) form the lanes `±(T_x/D)(O_x − O)` at that
/// frequency, integrated with the frequency rule's accepted weights
/// ([`optics::Polychromatic::mean_mtf_and_lanes`]): the difference formed per frequency, not of
/// two means, on the value's own error control. `O_x`'s kink at its cutoff `1/(xF#)` is one of
/// the rule's cuts (the band's edges are the lens's breakpoints, so spectral panel ends, whose
/// cutoffs cut the frequency range). `∂ln N = ±T_x/D`, `D` the engine's weight. `None` where
/// the engine is another or gives no such pass.
fn band_edges_on_value_pass(scene: &Scene, detected: &radiometry::Spectrum, (lo, hi): (f64, f64)) -> Option<EdgeLanes> {
    let (lens, field) = (scene.lens(), scene.field());
    if detected.as_line().is_some() {
        return None;
    }
    let settings = scene.options().settings();
    let nyquist = scene.camera().nyquist();
    // each edge's single wavelength (a line of any weight: its OTF is normalized)
    let line = |x: f64| radiometry::Line::new(x, 1e-9, 1.0).ok().map(radiometry::Spectrum::Line);
    let (line_lo, line_hi) = (line(lo)?, line(hi)?);
    let at_lo = optics::Polychromatic::with_settings(lens, &line_lo, field, nyquist, None, settings).ok()?;
    let at_hi = optics::Polychromatic::with_settings(lens, &line_hi, field, nyquist, None, settings).ok()?;
    if at_lo.direction_dependent() || at_hi.direction_dependent() {
        return None;
    }
    on_value_engine(scene, detected, settings, |poly| {
        if poly.engine() != optics::Engine::Exact1d || poly.spectral_ends().is_some() {
            return None;
        }
        let densities = edge_densities(scene, detected, (lo, hi), poly.total_weight());
        // an edge without detected light: its lane 0 (no line read)
        let lane =
            |d: f64, at: &optics::Polychromatic<'_>, nu: f64, o: f64| if d == 0.0 { 0.0 } else { d * (at.otf(nu) - o) };
        let (_, [d_lo, d_hi], _) =
            poly.mean_mtf_and_lanes(&|nu, o| [lane(densities[0], &at_lo, nu, o), lane(densities[1], &at_hi, nu, o)])?;
        if poly.over_budget().is_some() {
            return None;
        }
        Some(EdgeLanes { edges: [(densities[0], d_lo), (densities[1], d_hi)], design: None, aperture: None })
    })
}

/// `(∂M̄/∂ln F#, ∂M̄/∂ln f0)` where every order at every spectral node of the value's engine is
/// the full circular pupil without any wavefront error (a true achromat, β = 1: `W020 = 0`
/// across the band; docs/physics.md, "Gradients: the dispersion-engineered lens"). Each
/// wavelength's OTF is then the diffraction-limited `H(νλF#)`: at fixed wavefront the F-number
/// only scales the frequency, so by parts `∂M̄/∂ln F# = P(ν_N)|O(ν_N)| − M̄ − P_ν`
/// (`P_ν = (1/ν_N) ∫ ν P′ |O| dν`, 0 without the pixel MTF: on the value's engine), and the
/// defocus lane `D_K = (1/ν_N) ∫ P sign(O) ∂O/∂ln K dν` is 0 (`w ∂H/∂w = 0` at `w = 0`, `H`
/// being even in `w`): no integral to take for it. `None` where the scene is not that (a
/// line, an order with a wavefront error, image shifts, an OTF that depends on direction, the
/// field moving the OTF).
pub(super) fn aperture_without_defocus(
    scene: &Scene,
    e: &crate::Evaluation,
    p: Parameter,
) -> Result<Option<(f64, f64)>, Error> {
    let detected = crate::evaluate::detected_spectrum(scene);
    if detected.as_line().is_some() {
        return Ok(None);
    }
    let plain = scene.lens().orders(e.mean_wavelength_nm * 1e-9, scene.field()).iter().all(|o| {
        let w = &o.wavefront;
        // no defocus at the mean wavelength either: no engine is built for a lens that has some
        matches!(o.pupil, optics::Pupil::Full)
            && w.is_defocus_only()
            && w.defocus_m == 0.0
            && w.image_shift_m == [0.0, 0.0]
    });
    if !plain {
        return Ok(None);
    }
    let camera = scene.camera();
    let found = on_value_engine(scene, &detected, scene.options().settings(), |poly| {
        let still = scene.field().is_on_axis() || poly.field_independent();
        if poly.max_defocus() != 0.0 || poly.direction_dependent() || !still {
            return None;
        }
        let edge = poly.mtf(camera.nyquist());
        let pixel_slope = match camera.pixel_mtf() {
            false => Some(0.0),
            true => poly.mean_mtf_and_pixel_slope(0.0).map(|(_, slope, _)| slope),
        };
        Some((edge, pixel_slope))
    });
    let Some((edge, pixel_slope)) = found else { return Ok(None) };
    let pixel_slope = match pixel_slope {
        Some(s) => s,
        None => super::noise_weight::pixel_slope_white(scene, e, p)?,
    };
    Ok(Some((edge - e.mean_mtf - pixel_slope, 0.0)))
}
