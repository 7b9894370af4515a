//! The spatially multiplexed lens's keys (`lens.model = "multiplexed"`): which engine parameter
//! each sets, or why its gradient is refused (docs/physics.md, "Gradients: the multiplexed lens").
//!
//! Interleaved layout: every channel `j` is an order through the full circular pupil with the
//! defocus `W020_j(λ) = (1 − λ/λ_j) f0/(8F#²)`, the efficiency `τ_j = η/N²` and, off axis, the
//! lateral colour `Δ_j = f0 tan θ (λ_j/λ − 1)`: the chromatic and harmonic lenses' form, so the
//! F-number, the focal length and the field angles ride the same lanes of the exact 1-D engine
//! (`W020_j ∝ f0/F#²`, `Δ_j ∝ f0`, `∂Δ_j/∂θ = f0 sec²θ (λ_j/λ − 1)`); a channel's wavelength
//! λ_j moves its order alone, on axis the design wavelength's lane with that order's rates, off
//! axis with its one order's shift's lane beside it ([`with_channels`]). Both layouts: one `η`
//! for every channel scales every order's efficiency (and, segmented, every zone's amplitude
//! `√η` of one composite pupil whose OTF is normalized at zero frequency), so it leaves the OTF
//! as it is and moves the photon count alone, `N ∝ η`, as the chromatic lens's τ1; `T` moves the
//! transmitted light alone.

use anyhow::{Result, anyhow};
use metric::Parameter;

use super::{Chain, FIELD, Gradient, field_point, lookup};

/// The gradient where `keys` ask a channel's wavelength or own efficiency of an interleaved lens
/// (`lens.channels_nm[j]`, `lens.channel_efficiencies[j]`, or either list for every channel),
/// with its evaluation: on axis every channel key in one pass on the value's engine
/// ([`metric::channel_gradients`]: each order's design lane and own weight beside the value's
/// OTFs), else each by its own lane ([`metric::channel_wavelength_gradient`],
/// [`metric::channel_efficiency_gradient`]: the design wavelength's lane with the rates of that
/// channel's order alone), per nm or per unit η_j; the other keys as
/// [`super::gradient_and_evaluation`] takes them, in the keys' order; `None` where no key is a
/// channel's of an interleaved lens.
pub(super) fn with_channels(
    source: &scene::Source,
    overrides: &[String],
    keys: &[String],
) -> Result<Option<(Gradient, metric::Evaluation)>> {
    const CHANNELS: &str = "lens.channels_nm";
    const EFFICIENCIES: &str = "lens.channel_efficiencies";
    if !keys.iter().any(|k| k.trim().starts_with("lens.channel")) {
        return Ok(None);
    }
    let (table, built) = crate::objective::resolved_and_built(source, overrides)?;
    let model = lookup(&table, "lens.model").and_then(toml::Value::as_str);
    let layout = lookup(&table, "lens.layout").and_then(toml::Value::as_str);
    if model != Some("multiplexed") || layout != Some("interleaved") {
        return Ok(None);
    }
    let expanded = super::expand(source, &table, keys)?;
    // (the channel, whether it is its wavelength)
    let channel = |key: &str| {
        let entry = |list: &str| super::entry_of(key, list).and_then(Result::ok);
        entry(CHANNELS).map(|j| (j, true)).or_else(|| entry(EFFICIENCIES).map(|j| (j, false)))
    };
    // the F-number, focal length and aperture diameter: on axis on the channels' pass (their
    // chains on ln F# and ln f0 alone), else as the other keys
    let aperture_chain = |key: &str, value: f64| match chain(key, value, "multiplexed", &table) {
        Some(Ok(c)) if c.iter().all(|(p, _)| matches!(p, Parameter::FNumber | Parameter::FocalLength)) => Some(c),
        _ => None,
    };
    let others = |aperture: bool| -> Vec<String> {
        expanded
            .iter()
            .filter(|(k, v)| channel(k).is_none() && aperture_chain(k, *v).is_some() == aperture)
            .map(|(k, _)| k.clone())
            .collect()
    };
    let (plain, aperture) = (others(false), others(true));
    let rest = match plain.is_empty() {
        true => None,
        false => Some(super::gradient_and_evaluation(source, overrides, &plain)?),
    };
    let mut evaluation = rest.as_ref().map(|(_, e)| e.clone());
    // every channel key (and the aperture's) in one pass on the value's engine where it gives the
    // lanes (on axis); else each channel key by its own lane below, the aperture's as the others
    let nm = |v: &toml::Value| v.as_float().or_else(|| v.as_integer().map(|i| i as f64));
    let channels: Vec<f64> = lookup(&table, CHANNELS)
        .and_then(toml::Value::as_array)
        .map_or_else(Vec::new, |list| list.iter().filter_map(nm).map(|l| l * 1e-9).collect());
    let wanted: Vec<(usize, bool)> = expanded.iter().filter_map(|(k, _)| channel(k)).collect();
    let together = metric::channel_gradients(&built, &channels, &wanted, !aperture.is_empty(), evaluation.clone())
        .map_err(|e| {
            let key = expanded.iter().find(|(k, _)| channel(k).is_some()).map_or("", |(k, _)| k.as_str());
            anyhow!("--wrt {key}: {}: {e}", source.label())
        })?;
    let aside = match (&together, aperture.is_empty()) {
        (None, false) => Some(super::gradient_and_evaluation(source, overrides, &aperture)?),
        _ => None,
    };
    evaluation = evaluation.or_else(|| aside.as_ref().map(|(_, e)| e.clone()));
    let mut at_together = 0;
    let (mut d_asnr, mut d_mean_mtf, mut d_snr0, mut d_photoelectrons) = (vec![], vec![], vec![], vec![]);
    let (mut at_rest, mut at_aside) = (0, 0);
    for (key, value) in &expanded {
        if let (Some(_), Some(g)) = (channel(key), together.as_ref()) {
            // ∂/∂ln λ_j per nm, ∂/∂ln η_j per unit η_j
            d_asnr.push(g.asnr[at_together] / value);
            d_mean_mtf.push(g.mean_mtf[at_together] / value);
            d_snr0.push(g.snr0[at_together] / value);
            d_photoelectrons.push(g.photoelectrons[at_together] / value);
            at_together += 1;
            evaluation.get_or_insert_with(|| g.evaluation.clone());
        } else if let Some((j, wavelength)) = channel(key) {
            let g = match wavelength {
                true => metric::channel_wavelength_gradient(&built, j, value * 1e-9),
                false => metric::channel_efficiency_gradient(&built, j),
            }
            // the design wavelength's refusals, of this channel's
            .map_err(|e| {
                anyhow!("--wrt {key}: {}: {}", source.label(), e.to_string().replace("lens.design_wavelength_nm", key))
            })?;
            // ∂/∂ln λ_j per nm, ∂/∂ln η_j per unit η_j
            d_asnr.push(g.asnr[0] / value);
            d_mean_mtf.push(g.mean_mtf[0] / value);
            d_snr0.push(g.snr0[0] / value);
            d_photoelectrons.push(g.photoelectrons[0] / value);
            evaluation.get_or_insert(g.evaluation);
        } else if let (Some(c), Some(g)) = (aperture_chain(key, *value), together.as_ref()) {
            // ∂/∂key = Σ c ∂/∂p over the key's chain, ln F# and ln f0 after the channels' lanes
            let at = |p: &Parameter| wanted.len() + usize::from(*p == Parameter::FocalLength);
            let per_key = |d: &[f64]| c.iter().map(|(p, k)| k * d[at(p)]).sum::<f64>() + 0.0;
            d_asnr.push(per_key(&g.asnr));
            d_mean_mtf.push(per_key(&g.mean_mtf));
            d_snr0.push(per_key(&g.snr0));
            d_photoelectrons.push(per_key(&g.photoelectrons));
        } else {
            let (g, at) = match aperture_chain(key, *value) {
                Some(_) => (&aside.as_ref().expect("the aperture keys' gradient").0, &mut at_aside),
                None => (&rest.as_ref().expect("the other keys' gradient").0, &mut at_rest),
            };
            d_asnr.push(g.d_asnr[*at]);
            d_mean_mtf.push(g.d_mean_mtf[*at]);
            d_snr0.push(g.d_snr0[*at]);
            d_photoelectrons.push(g.d_photoelectrons[*at]);
            *at += 1;
        }
    }
    let e = evaluation.expect("at least one key");
    let gradient = Gradient::of(&expanded, &e, [d_asnr, d_mean_mtf, d_snr0, d_photoelectrons]);
    Ok(Some((gradient, e)))
}

/// The gradient where `keys` ask a channel's wavelength or own efficiency or a zone's area
/// fraction of a segmented lens (`lens.channels_nm[j]`, `lens.channel_efficiencies[j]`,
/// `lens.area_fractions[j]`, or a list for every channel), with its evaluation: each a lane on
/// the zones inside the composite pupil on the FFT path, on axis and off
/// ([`metric::zone_key_gradient`], per `ln λ_j`, `ln η_j` or `ln a_j`, here per nm or per unit
/// η_j or a_j: an area fraction moves the zones' edges), the other keys as [`super::gradient_and_evaluation`] takes them, in the keys'
/// order; `None` where no key is a channel's or a zone's of a segmented lens.
pub(super) fn with_zone_channels(
    source: &scene::Source,
    overrides: &[String],
    keys: &[String],
) -> Result<Option<(Gradient, metric::Evaluation)>> {
    if !keys.iter().any(|k| k.trim().starts_with("lens.channel") || k.trim().starts_with("lens.area_fractions")) {
        return Ok(None);
    }
    let (table, built) = crate::objective::resolved_and_built(source, overrides)?;
    let model = lookup(&table, "lens.model").and_then(toml::Value::as_str);
    let layout = lookup(&table, "lens.layout").and_then(toml::Value::as_str);
    if model != Some("multiplexed") || layout != Some("segmented") {
        return Ok(None);
    }
    let expanded = super::expand(source, &table, keys)?;
    let zone_key = |key: &str| {
        let entry = |list: &str| super::entry_of(key, list).and_then(Result::ok);
        entry("lens.channels_nm")
            .map(metric::ZoneKey::ChannelWavelength)
            .or_else(|| entry("lens.channel_efficiencies").map(metric::ZoneKey::ChannelEfficiency))
            .or_else(|| entry("lens.area_fractions").map(metric::ZoneKey::AreaFraction))
    };
    let others: Vec<String> = expanded.iter().filter(|(k, _)| zone_key(k).is_none()).map(|(k, _)| k.clone()).collect();
    let rest = match others.is_empty() {
        true => None,
        false => Some(super::gradient_and_evaluation(source, overrides, &others)?),
    };
    let mut evaluation = rest.as_ref().map(|(_, e)| e.clone());
    let mut columns: [Vec<f64>; 4] = Default::default();
    let mut at_rest = 0;
    for (key, value) in &expanded {
        let column = if let Some(zone) = zone_key(key) {
            let g =
                metric::zone_key_gradient(&built, zone).map_err(|e| anyhow!("--wrt {key}: {}: {e}", source.label()))?;
            evaluation.get_or_insert(g.evaluation);
            // ∂/∂ln λ_j per nm, ∂/∂ln η_j per unit η_j, ∂/∂ln a_j per unit a_j
            [g.asnr[0], g.mean_mtf[0], g.snr0[0], g.photoelectrons[0]].map(|d| d / value)
        } else {
            let (g, _) = rest.as_ref().expect("the other keys' gradient");
            at_rest += 1;
            [&g.d_asnr, &g.d_mean_mtf, &g.d_snr0, &g.d_photoelectrons].map(|d| d[at_rest - 1])
        };
        for (c, d) in columns.iter_mut().zip(column) {
            c.push(d);
        }
    }
    let e = evaluation.expect("at least one key");
    Ok(Some((Gradient::of(&expanded, &e, columns), e)))
}

/// The chain of `key` (at `value`) of a multiplexed lens, or why it is refused; `None` for a key
/// that is not the lens's or another family's lens.
pub(super) fn chain(key: &str, value: f64, lens_model: &str, table: &toml::Table) -> Option<Result<Chain>> {
    if lens_model != "multiplexed" {
        return None;
    }
    let diameter_given = lookup(table, "lens.aperture_diameter_mm").is_some();
    // the field angles: every channel's lateral colour on the exact 1-D engine (interleaved), or
    // every zone's tilt by its own rate f0 sec²θ (λ_j/λ − 1) on the FFT path (segmented,
    // `optics::LensModel::zone_rates`), and the relative illumination
    match key {
        // one η for every channel: N ∝ η, the OTF unmoved (module docs)
        "lens.efficiency" => Some(Ok(vec![(Parameter::Efficiency, 1.0 / value)])),
        "lens.transmission" => Some(Ok(vec![(Parameter::Transmission, 1.0 / value)])),
        // every zone's defocus and tilt scale with f0/F#² and f0/F# (segmented: the zones' lanes
        // on the FFT path, `metric` `aperture_on_zones`)
        "lens.f_number" => Some(Ok(vec![(Parameter::FNumber, 1.0 / value)])),
        // F# = f0/D where the diameter is given: ∂/∂ln f0 = ∂/∂ln f0|F# + ∂/∂ln F#
        "lens.focal_length_mm" if diameter_given => {
            Some(Ok(vec![(Parameter::FocalLength, 1.0 / value), (Parameter::FNumber, 1.0 / value)]))
        }
        "lens.focal_length_mm" => Some(Ok(vec![(Parameter::FocalLength, 1.0 / value)])),
        // ∂/∂D = −(1/D) ∂/∂ln F#
        "lens.aperture_diameter_mm" => Some(Ok(vec![(Parameter::FNumber, -1.0 / value)])),
        _ => {
            if let Some((_, axis)) = FIELD.iter().find(|(k, _)| *k == key) {
                let p = Parameter::FieldAngle(*axis);
                return Some(Ok(super::direct(p, value)));
            }
            if key.starts_with("fields") {
                return match field_point(key) {
                    Ok(Some((point, axis))) => {
                        Some(Ok(super::direct(Parameter::FieldPointAngle { point, axis }, value)))
                    }
                    Ok(None) => None,
                    Err(e) => Some(Err(e)),
                };
            }
            // (a channel's wavelength and own efficiency and a zone's area fraction: `with_channels`,
            // interleaved, and `with_zone_channels`, segmented)
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use scene::Source;
    use scene::sweep::assignment;

    use super::super::gradient;

    /// The tolerance of the converged evaluations the references difference (docs/physics.md,
    /// "Gradients": ≤ 1e-10).
    const REFERENCE_TOLERANCE: f64 = 1e-10;

    /// The two multiplexed designs of examples/designs.toml (750/800/850 nm, F/2.5, η = 0.15,
    /// T = 0.55), `layout` with `zones`, in the paper's theory scene (examples/paper-theory.toml)
    /// in place of its lens, written here.
    fn multiplexed(layout: &str) -> Source {
        multiplexed_with(layout, "efficiency = 0.15")
    }

    /// [`multiplexed`] with the efficiency given by `efficiency` (a line of `[lens]`).
    fn multiplexed_with(layout: &str, efficiency: &str) -> Source {
        let paper = scene::read(None).unwrap();
        let rest = paper.text().split_once("[source]").unwrap().1;
        let zones = if layout == "segmented" { "zones = \"concentric\"\n" } else { "" };
        Source::from_text(
            format!(
                "title = \"multiplexed {layout}\"\n[lens]\nmodel = \"multiplexed\"\nlayout = \"{layout}\"\n{zones}\
                 f_number = 2.5\nfocal_length_mm = 3.36\nchannels_nm = [750.0, 800.0, 850.0]\n{efficiency}\n\
                 transmission = 0.55\n\n[source]{rest}"
            ),
            "multiplexed lens written in the test",
            ".",
        )
    }

    fn owned(list: &[&str]) -> Vec<String> {
        list.iter().map(|s| (*s).to_owned()).collect()
    }

    /// (ASNR, mean MTF, SNR0, N) of an evaluation at `tolerance` with `key = value`.
    fn evaluated(source: &Source, overrides: &[&str], key: &str, value: f64, tolerance: f64) -> [f64; 4] {
        let mut set: Vec<String> = overrides
            .iter()
            .filter(|o| o.split_once('=').is_none_or(|(k, _)| k.trim() != key))
            .map(|o| (*o).to_owned())
            .collect();
        set.push(format!("options.tolerance={tolerance:e}"));
        set.push(assignment(key, value));
        let e = metric::evaluate(&scene::build_from(source, &set).unwrap()).unwrap();
        [e.asnr, e.mean_mtf, e.snr0, e.photoelectrons]
    }

    /// The reference written here: central differences with step `h` of evaluations at
    /// `tolerance`; for a field angle and a channel's wavelength (whose steps are not relative to
    /// the key)
    /// Richardson-extrapolated from the steps `2h` and `h` (`(4 D(h) − D(2h))/3`).
    fn reference(source: &Source, overrides: &[&str], key: &str, value: f64, h: f64, tolerance: f64) -> [f64; 4] {
        let central = |h: f64| -> [f64; 4] {
            let up = evaluated(source, overrides, key, value + h, tolerance);
            let down = evaluated(source, overrides, key, value - h, tolerance);
            std::array::from_fn(|q| (up[q] - down[q]) / (2.0 * h))
        };
        if !(key.starts_with("field") || key.starts_with("lens.channels_nm")) {
            return central(h);
        }
        let (coarse, fine) = (central(2.0 * h), central(h));
        std::array::from_fn(|q| (4.0 * fine[q] - coarse[q]) / 3.0)
    }

    /// Every key's gradient at the scene tolerance `tolerance` against [`reference`] (step
    /// `step(key, value)`, evaluations at `reference_tolerance`), within 10× `tolerance` of the
    /// gradient's norm per quantity (the quantity itself where the gradient is 0).
    fn check(
        source: &Source,
        overrides: &[&str],
        keys: &[&str],
        tolerance: f64,
        reference_tolerance: f64,
        step: &dyn Fn(&str, f64) -> f64,
    ) -> super::super::Gradient {
        let mut set = owned(overrides);
        set.push(format!("options.tolerance={tolerance:e}"));
        let g = gradient(source, &set, &owned(keys)).unwrap();
        assert_eq!(g.keys, owned(keys));
        let references: Vec<[f64; 4]> = g
            .keys
            .iter()
            .zip(&g.values)
            .map(|(k, v)| reference(source, overrides, k, *v, step(k, *v), reference_tolerance))
            .collect();
        let ours = [&g.d_asnr, &g.d_mean_mtf, &g.d_snr0, &g.d_photoelectrons];
        let mut failures = Vec::new();
        for (q, name) in ["ASNR", "mean MTF", "SNR0", "N"].iter().enumerate() {
            // as relative sensitivities ∂/∂ln key, except the field angles (0 on axis)
            let scale = |i: usize| if g.keys[i].starts_with("field") { 1.0 } else { g.values[i] };
            let mine: Vec<f64> = (0..g.keys.len()).map(|i| ours[q][i] * scale(i)).collect();
            let theirs: Vec<f64> = (0..g.keys.len()).map(|i| references[i][q] * scale(i)).collect();
            let norm = match mine.iter().map(|x| x * x).sum::<f64>().sqrt() {
                0.0 => [g.asnr, g.mean_mtf, g.snr0, g.photoelectrons][q],
                norm => norm,
            };
            for (i, k) in g.keys.iter().enumerate() {
                let error = (mine[i] - theirs[i]).abs() / norm;
                println!("{name} {k}: gradient {:.9e}, differences {:.9e}, error/norm {error:.1e}", mine[i], theirs[i]);
                if error > 10.0 * tolerance {
                    failures.push(format!("{name} {k}: {} vs {} (norm {norm})", mine[i], theirs[i]));
                }
            }
        }
        assert!(failures.is_empty(), "{failures:#?}");
        g
    }

    /// A key on which the value varies on the scale of the key itself: h ≈ 6.7e-4 |v|
    /// (docs/physics.md, "Gradients"); 0.02° for a field angle (the mean MTF turns on degrees);
    /// 0.05 nm for a channel's wavelength (the mean MTF turns on the band's scale, nm).
    fn step(key: &str, value: f64) -> f64 {
        if key.starts_with("field") {
            0.02
        } else if key.starts_with("lens.channels_nm") {
            0.05
        } else {
            (3.0 * REFERENCE_TOLERANCE).cbrt() * value.abs()
        }
    }

    /// The interleaved lens on axis on a 10 nm band (the exact 1-D engine): the F-number and
    /// focal length (every channel's `W020_j ∝ f0/F#²`, `N ∝ 1/F#²`), the one efficiency η (N
    /// alone) and the transmission (the stray light alone: glare included, read noise), at the
    /// scene's 1e-6 against differences of evaluations at 1e-10.
    #[test]
    fn interleaved_lens_keys_match_central_differences() {
        let source = multiplexed("interleaved");
        let overrides = ["spectrum.range_nm=10", "options.glare=\"included\"", "camera.read_noise_e=2"];
        let keys = ["lens.f_number", "lens.focal_length_mm", "lens.efficiency", "lens.transmission"];
        let g = check(&source, &overrides, &keys, 1e-6, REFERENCE_TOLERANCE, &step);
        // the defocus moves the mean MTF; η and T do not
        assert!(g.d_mean_mtf[0] != 0.0 && g.d_mean_mtf[1] != 0.0, "{g:?}");
        assert!(g.d_mean_mtf[2] == 0.0 && g.d_mean_mtf[3] == 0.0 && g.d_snr0[3] < 0.0, "{g:?}");
    }

    /// The interleaved lens off axis at (2°, 1°) with cos⁴θ on a 4 nm band: each channel's
    /// lateral colour `f0 tan θ (λ_j/λ − 1)` moves with the field angles
    /// (`∂Δ_j/∂θ = f0 sec²θ (λ_j/λ − 1)`) and with f0 (not F#), on the exact 1-D engine's lanes.
    #[test]
    fn interleaved_lens_off_axis_matches_central_differences() {
        let source = multiplexed("interleaved");
        let overrides =
            ["spectrum.range_nm=4", "field.x_deg=2", "field.y_deg=1", "lens.relative_illumination=\"cos4\""];
        let keys = ["field.x_deg", "field.y_deg", "lens.f_number", "lens.focal_length_mm"];
        let g = check(&source, &overrides, &keys, 1e-6, REFERENCE_TOLERANCE, &step);
        assert!(g.d_mean_mtf.iter().all(|d| *d != 0.0), "{g:?}");
    }

    /// The interleaved lens's channel wavelengths on axis on a 10 nm band, with the F-number
    /// among them (the keys' order kept): λ_j moves channel j's defocus alone,
    /// `∂W020_j/∂ln λ_j = (λ/λ_j) f0/(8F#²)`, the design wavelength's lane with that order's
    /// rates; against differences of evaluations at 1e-10 at the step 6.7e-4 λ_j.
    #[test]
    fn interleaved_channel_wavelengths_match_central_differences() {
        let source = multiplexed("interleaved");
        let overrides = ["spectrum.range_nm=10", "camera.read_noise_e=2"];
        let keys = ["lens.channels_nm[0]", "lens.f_number", "lens.channels_nm[1]", "lens.channels_nm[2]"];
        let g = check(&source, &overrides, &keys, 1e-6, REFERENCE_TOLERANCE, &step);
        // λ_j moves the OTF alone; the channel in focus at the band's centre (800 nm) least,
        // the mean MTF near its peak in λ_1 there
        let least = g.d_mean_mtf[2].abs() < g.d_mean_mtf[0].abs().min(g.d_mean_mtf[3].abs());
        assert!(g.d_photoelectrons[0] == 0.0 && least, "{g:?}");
        let all = gradient(&source, &owned(&overrides), &owned(&["lens.channels_nm"])).unwrap();
        assert_eq!(all.keys, owned(&["lens.channels_nm[0]", "lens.channels_nm[1]", "lens.channels_nm[2]"]));
        assert_eq!(all.d_asnr, [g.d_asnr[0], g.d_asnr[2], g.d_asnr[3]]);
    }

    /// The interleaved lens's channel wavelengths and own efficiencies off axis at 3° on a 4 nm
    /// band with the stray light and read noise: λ_j moves channel j's
    /// defocus and its lateral colour `Δ_j = f0 tan θ (λ_j/λ − 1)` alone
    /// (`∂Δ_j/∂ln λ_j = f0 tan θ λ_j/λ`, one order's shift against the others'), η_j its weight
    /// alone; on the exact 1-D engine's lanes, against differences of evaluations at 1e-10.
    #[test]
    fn interleaved_channels_off_axis_match_central_differences() {
        let source = multiplexed_with("interleaved", "channel_efficiencies = [0.1, 0.15, 0.2]");
        let overrides = ["spectrum.range_nm=4", "field.x_deg=3", "options.glare=\"included\"", "camera.read_noise_e=2"];
        let keys = [
            "lens.channels_nm[0]",
            "lens.channels_nm[1]",
            "lens.channels_nm[2]",
            "lens.channel_efficiencies[0]",
            "lens.channel_efficiencies[1]",
        ];
        let g = check(&source, &overrides, &keys, 1e-6, REFERENCE_TOLERANCE, &step);
        // λ_j moves the OTF alone (N held); every key moves the mean MTF
        assert!(g.d_photoelectrons[..3] == [0.0; 3] && g.d_mean_mtf.iter().all(|d| *d != 0.0), "{g:?}");
        // off axis the far channels' lateral colour moves with λ_j: their lanes are not the
        // on-axis ones
        let on_axis = gradient(&source, &owned(&["spectrum.range_nm=4"]), &owned(&["lens.channels_nm[0]"])).unwrap();
        assert!((on_axis.d_mean_mtf[0] - g.d_mean_mtf[0]).abs() > 1e-3 * g.d_mean_mtf[0].abs(), "{on_axis:?} {g:?}");
    }

    /// The interleaved lens with Zernike terms (Z4 0.02 µm, Z8 0.01 µm on every channel's order:
    /// the overlap engine, the OTF depending on direction) on axis on a 2 nm band, with the pixel
    /// MTF: λ_j moves channel j's own defocus alone (the terms are µm RMS, keys of their own), the
    /// design wavelength's lane on the overlap engine's nodes with that order's rates, and η_j
    /// its weight alone; against differences of evaluations at 1e-10.
    #[test]
    fn interleaved_channels_with_zernike_terms_match_central_differences() {
        let zernike = "channel_efficiencies = [0.1, 0.15, 0.2]\nzernike_noll_rms_um = [0, 0, 0, 0.02, 0, 0, 0, 0.01]";
        let source = multiplexed_with("interleaved", zernike);
        let overrides = ["spectrum.range_nm=2", "camera.pixel_mtf=true"];
        let keys = ["lens.channels_nm[2]", "lens.channel_efficiencies[1]"];
        let g = check(&source, &overrides, &keys, 1e-6, REFERENCE_TOLERANCE, &step);
        // λ_j moves the OTF alone (N held); every key moves the mean MTF
        assert!(g.d_photoelectrons[0] == 0.0 && g.d_mean_mtf.iter().all(|d| *d != 0.0), "{g:?}");
    }

    /// The interleaved lens's channel keys over a `[[fields]]` list (on axis, weight 1, and at 3°,
    /// weight 0.5) on a 4 nm band: the weighted mean of each point's gradient, as the value is
    /// of the points' values.
    #[test]
    fn interleaved_channels_over_a_field_list_match_central_differences() {
        let one = multiplexed_with("interleaved", "channel_efficiencies = [0.1, 0.15, 0.2]");
        let text =
            format!("{}\n[[fields]]\nx_deg = 0\nweight = 1\n\n[[fields]]\nx_deg = 3\nweight = 0.5\n", one.text());
        let source = Source::from_text(text, "multiplexed lens over a field list written in the test", ".");
        let keys = ["lens.channels_nm[0]", "lens.channel_efficiencies[1]"];
        let g = check(&source, &["spectrum.range_nm=4"], &keys, 1e-6, REFERENCE_TOLERANCE, &step);
        assert!(g.d_mean_mtf.iter().all(|d| *d != 0.0), "{g:?}");
    }

    /// The interleaved lens's channels' own efficiencies on axis on a 10 nm band with the stray
    /// light and read noise, with T among them: η_j moves channel j's weight alone
    /// (`∂τ_j/∂ln η_j = τ_j`), so the OTF's weights, N and the stray light; the design
    /// wavelength's lane with the rates `[0, τ_j]` of that order.
    #[test]
    fn interleaved_channel_efficiencies_match_central_differences() {
        let source = multiplexed_with("interleaved", "channel_efficiencies = [0.1, 0.15, 0.2]");
        let overrides = ["spectrum.range_nm=10", "options.glare=\"included\"", "camera.read_noise_e=2"];
        let keys = ["lens.channel_efficiencies", "lens.transmission"];
        let mut set = owned(&overrides);
        set.push("options.tolerance=1e-6".to_owned());
        let listed = gradient(&source, &set, &owned(&keys)).unwrap();
        let each = ["lens.channel_efficiencies[0]", "lens.channel_efficiencies[1]", "lens.channel_efficiencies[2]"];
        assert_eq!(listed.keys[..3], owned(&each));
        let g =
            check(&source, &overrides, &[&each[..], &["lens.transmission"]].concat(), 1e-6, REFERENCE_TOLERANCE, &step);
        assert_eq!(listed.d_asnr, g.d_asnr);
        // the in-focus channel's weight raises the mean MTF, the defocused ones' lower it
        assert!(g.d_mean_mtf[1] > 0.0 && g.d_mean_mtf[0] < 0.0 && g.d_mean_mtf[2] < 0.0, "{g:?}");
    }

    /// On axis every channel key in one pass (`metric::channel_gradients`: each order's design
    /// lane and own weight beside the value's OTFs) gives each key's own lane
    /// (`metric::channel_wavelength_gradient`, `metric::channel_efficiency_gradient`, held against
    /// central differences above) within 1e-12 of each quantity's norm over the keys, on the
    /// paper's 50 nm band (the per-frequency product rule, as the tests above on 10 nm); off
    /// axis it leaves the keys to their own lanes.
    #[test]
    fn interleaved_channels_on_axis_in_one_pass() {
        let source = multiplexed_with("interleaved", "channel_efficiencies = [0.1, 0.15, 0.2]");
        let set = owned(&["options.glare=\"included\"", "camera.read_noise_e=2"]);
        let built = scene::build_from(&source, &set).unwrap();
        let channels = [750e-9, 800e-9, 850e-9];
        let wanted = [(0, true), (1, true), (2, true), (0, false), (1, false), (2, false)];
        let together = metric::channel_gradients(&built, &channels, &wanted, false, None).unwrap().expect("on axis");
        let each: Vec<metric::Gradient> = wanted
            .iter()
            .map(|&(j, wavelength)| match wavelength {
                true => metric::channel_wavelength_gradient(&built, j, channels[j]).unwrap(),
                false => metric::channel_efficiency_gradient(&built, j).unwrap(),
            })
            .collect();
        assert_eq!(together.evaluation, each[0].evaluation);
        let quantities =
            |g: &metric::Gradient| [g.asnr.clone(), g.mean_mtf.clone(), g.snr0.clone(), g.photoelectrons.clone()];
        let ours = quantities(&together);
        for (q, name) in ["ASNR", "mean MTF", "SNR0", "N"].iter().enumerate() {
            let theirs: Vec<f64> = each.iter().map(|g| quantities(g)[q][0]).collect();
            let norm = theirs.iter().map(|x| x * x).sum::<f64>().sqrt();
            assert!(norm > 0.0, "{name}");
            for (i, (a, b)) in ours[q].iter().zip(&theirs).enumerate() {
                assert!((a - b).abs() <= 1e-12 * norm, "{name} {:?}: {a:e} vs {b:e}", wanted[i]);
            }
        }
        let off = scene::build_from(&source, &owned(&["field.x_deg=3"])).unwrap();
        assert!(metric::channel_gradients(&off, &channels, &wanted, false, None).unwrap().is_none());
    }

    /// The interleaved lens's F-number and focal length asked with a channel's wavelength on axis
    /// ride the channels' pass (`metric::channel_gradients` with the aperture: the defocus lane
    /// and `P_ν` beside each order's lanes, `∂M̄/∂ln F# = P(ν_N)|O(ν_N)| − M̄ − P_ν − 2 D_K`,
    /// `∂M̄/∂ln f0 = D_K`): on a 10 nm band with the pixel MTF, the stray light and read noise,
    /// against differences of evaluations at 1e-10, and the same as the scene's own gradient of
    /// the two keys (their pass of their own, `defocus_on_value_rule`) within 1e-9 of the norm.
    #[test]
    fn interleaved_aperture_on_the_channels_pass_matches_central_differences() {
        let source = multiplexed("interleaved");
        let overrides =
            ["spectrum.range_nm=10", "options.glare=\"included\"", "camera.read_noise_e=2", "camera.pixel_mtf=true"];
        let keys = ["lens.focal_length_mm", "lens.channels_nm[1]", "lens.f_number"];
        let g = check(&source, &overrides, &keys, 1e-6, REFERENCE_TOLERANCE, &step);
        let alone = gradient(&source, &owned(&overrides), &owned(&["lens.focal_length_mm", "lens.f_number"])).unwrap();
        let norm = alone.d_asnr.iter().map(|d| d * d).sum::<f64>().sqrt();
        for (a, b) in [g.d_asnr[0], g.d_asnr[2]].iter().zip(&alone.d_asnr) {
            assert!((a - b).abs() <= 1e-9 * norm, "{a:e} vs {b:e}");
        }
        assert!(g.d_mean_mtf[0] != 0.0 && g.d_snr0[2] < 0.0, "{g:?}");
    }

    /// The segmented lens (concentric zones, one composite pupil on the FFT path) on a 4 nm band:
    /// η and T move N and the stray light alone (the composite pupil's amplitude √η is uniform
    /// and its OTF normalized at zero frequency), so at a fixed sampling (64 pupil samples: the
    /// FFT path's discrete rule, the same at every step) the differences are the photon counts'
    /// and the value's discrete rule's exactly; the gradient within 10× 1e-4, the FFT path's
    /// tolerance (measured: ≤ 1e-12 of the norm).
    #[test]
    fn segmented_lens_efficiency_and_transmission_match_central_differences() {
        let source = multiplexed("segmented");
        for other in ["signal", "background"] {
            let channels = format!("lens.other_channels=\"{other}\"");
            let overrides = [
                "spectrum.range_nm=4",
                "options.pupil_samples=64",
                "options.glare=\"included\"",
                "camera.read_noise_e=2",
                &channels,
            ];
            let g = check(&source, &overrides, &["lens.efficiency", "lens.transmission"], 1e-4, 1e-4, &step);
            assert!(g.d_mean_mtf == [0.0, 0.0] && g.d_photoelectrons[0] > 0.0, "{g:?}");
        }
    }

    /// `source`'s gradient over `keys` under `overrides` against Richardson central differences
    /// (relative steps 4e-6 and 2e-6) of evaluations on the same fixed pupil sampling
    /// (`options.pupil_samples` among `overrides`), for ∂ASNR, ∂M̄, ∂SNR0 and ∂N, within
    /// `bound(key)` of each quantity's gradient norm, as ∂/∂ln key.
    fn matches_the_fixed_rule(
        source: &Source,
        overrides: &[&str],
        keys: &[&str],
        bound: &dyn Fn(&str) -> f64,
    ) -> super::super::Gradient {
        let g = gradient(source, &owned(overrides), &owned(keys)).unwrap();
        let references = super::super::tests::fixed_rule_references(source, &owned(overrides), &g);
        let ours = [&g.d_asnr, &g.d_mean_mtf, &g.d_snr0, &g.d_photoelectrons];
        let mut failures = Vec::new();
        for (q, name) in ["ASNR", "mean MTF", "SNR0", "N"].iter().enumerate() {
            let mine: Vec<f64> = (0..g.keys.len()).map(|i| ours[q][i] * g.values[i]).collect();
            let theirs: Vec<f64> = (0..g.keys.len()).map(|i| references[i][q] * g.values[i]).collect();
            let norm = mine.iter().map(|x| x * x).sum::<f64>().sqrt();
            assert!(norm > 0.0, "{name}: {g:?}");
            for (i, k) in g.keys.iter().enumerate() {
                let error = (mine[i] - theirs[i]).abs() / norm;
                println!("{name} {k}: gradient {:.9e}, differences {:.9e}, error/norm {error:.1e}", mine[i], theirs[i]);
                if error > bound(k) {
                    failures.push(format!("{name} {k}: {} vs {} (norm {norm})", mine[i], theirs[i]));
                }
            }
        }
        assert!(failures.is_empty(), "{failures:#?}");
        g
    }

    /// The bound of the zones' aperture lanes against the discrete rule's differences: the lanes
    /// (each zone's defocus and tilt, and the frequency scale s = νλF# on the value's grids and
    /// fixed rule) are the rule's exact derivative, so the differences' truncation and rounding
    /// remain (f0 and η measured ≤ 1.3e-10 of the norm, 1e-8 asserted; F# ≤ 4.7e-6, the
    /// interpolant's slope kinking at the grids' cell edges which the readings cross as F#
    /// moves, 1e-5 asserted as the phase lens's off axis; the field angles through sectors off
    /// axis ≤ 3.3e-7, the same kink as the value's azimuths turn with the field direction
    /// across the grids' cells, 1e-6 asserted; through rings ≤ 1.2e-10; the channels' keys
    /// ≤ 1.2e-10).
    fn exact_lanes(key: &str) -> f64 {
        match key {
            "lens.f_number" => 1e-5,
            k if k.starts_with("field") => 1e-6,
            _ => 1e-8,
        }
    }

    /// The segmented lens's F-number and focal length on axis (concentric zones, and sectors with
    /// the pixel MTF) on a 4 nm band: every zone's defocus `W020_j ∝ f0/F#²` moves by itself
    /// inside the composite pupil (the zones' defocus lane on the FFT path), F# also moves
    /// s = νλF# (the grids' readings on the value's rule) and N ∝ 1/F#²; against the discrete rule's differences at 64 pupil
    /// samples ([`exact_lanes`]).
    #[test]
    fn segmented_f_number_and_focal_length_on_axis() {
        let source = multiplexed("segmented");
        let keys = ["lens.f_number", "lens.focal_length_mm", "lens.efficiency"];
        for at in [&["lens.zones=\"concentric\""][..], &["lens.zones=\"sectors\"", "camera.pixel_mtf=true"][..]] {
            let mut overrides = vec!["spectrum.range_nm=4", "options.pupil_samples=64", "camera.read_noise_e=2"];
            overrides.extend(at);
            let g = matches_the_fixed_rule(&source, &overrides, &keys, &exact_lanes);
            // the defocus moves the mean MTF, η does not
            assert!(g.d_mean_mtf[0] != 0.0 && g.d_mean_mtf[1] != 0.0 && g.d_mean_mtf[2] == 0.0, "{g:?}");
        }
    }

    /// The segmented lens's F-number and focal length off axis at (2°, 1°) with cos⁴θ on a 4 nm
    /// band, concentric and sectors: each zone's tilt, its lateral colour `f0 tan θ (λ_j/λ − 1)`
    /// times NA, scales with f0/F# (the zones' tilt lane beside the defocus lane); against the
    /// discrete rule's differences as on axis.
    #[test]
    fn segmented_f_number_and_focal_length_off_axis() {
        let source = multiplexed("segmented");
        let keys = ["lens.f_number", "lens.focal_length_mm"];
        for zones in ["lens.zones=\"concentric\"", "lens.zones=\"sectors\""] {
            let overrides = [
                "spectrum.range_nm=4",
                "options.pupil_samples=64",
                "field.x_deg=2",
                "field.y_deg=1",
                "lens.relative_illumination=\"cos4\"",
                zones,
            ];
            matches_the_fixed_rule(&source, &overrides, &keys, &exact_lanes);
        }
    }

    /// The segmented lens's field angles off axis at (2°, 1°) with cos⁴θ on a 4 nm band,
    /// concentric and sectors, with the focal length: each zone's tilt moves at its own rate
    /// `f0 sec²θ (λ_j/λ − 1)` times NA (a lane with a rate per zone, `LensModel::zone_rates`),
    /// the value's azimuths turn with the field direction and the relative illumination moves N;
    /// against the discrete rule's differences at 64 pupil samples ([`exact_lanes`]).
    #[test]
    fn segmented_field_angles_off_axis() {
        // (the field point in the scene: the references set the keys differenced)
        let text = format!("{}\n[field]\nx_deg = 2\ny_deg = 1\n", multiplexed("segmented").text());
        let source = Source::from_text(text, "segmented lens off axis written in the test", ".");
        let keys = ["field.x_deg", "field.y_deg", "lens.focal_length_mm"];
        for zones in ["lens.zones=\"concentric\"", "lens.zones=\"sectors\""] {
            let overrides =
                ["spectrum.range_nm=4", "options.pupil_samples=64", "lens.relative_illumination=\"cos4\"", zones];
            let g = matches_the_fixed_rule(&source, &overrides, &keys, &exact_lanes);
            assert!(g.d_mean_mtf[0] != 0.0 && g.d_mean_mtf[1] != 0.0 && g.d_photoelectrons[0] < 0.0, "{g:?}");
        }
    }

    /// The segmented lens's channel wavelengths and own efficiencies on axis and off axis at
    /// (2°, 1°) on a 4 nm band with the stray light and read noise, concentric and sectors: λ_j
    /// moves zone j's defocus `(λ/λ_j) f0/(8F#²)` and tilt `f0 tan θ λ_j/λ` alone, η_j zone j's
    /// amplitude `√η_j` against the others' and the order's efficiency `Σ a_k η_k` (N's share
    /// `a_j η_j/Σ a_k η_k`); lanes with a rate on zone j alone, against the discrete rule's
    /// differences at 64 pupil samples ([`exact_lanes`]).
    #[test]
    fn segmented_channels_match_the_fixed_rule() {
        let source = multiplexed_with("segmented", "channel_efficiencies = [0.1, 0.15, 0.2]");
        let keys = ["lens.channels_nm[0]", "lens.channels_nm[1]", "lens.channel_efficiencies[0]", "lens.f_number"];
        for zones in ["lens.zones=\"concentric\"", "lens.zones=\"sectors\""] {
            for field in [&[][..], &["field.x_deg=2", "field.y_deg=1"][..]] {
                let mut overrides = vec![
                    "spectrum.range_nm=4",
                    "options.pupil_samples=64",
                    "options.glare=\"included\"",
                    "camera.read_noise_e=2",
                    zones,
                ];
                overrides.extend(field);
                let g = matches_the_fixed_rule(&source, &overrides, &keys, &exact_lanes);
                // λ_j moves the OTF alone; η_j the OTF's weights and N
                assert!(g.d_photoelectrons[..2] == [0.0; 2] && g.d_photoelectrons[2] > 0.0, "{g:?}");
                assert!(g.d_mean_mtf.iter().all(|d| *d != 0.0), "{g:?}");
            }
        }
    }

    /// The segmented lens's channel keys and a point's field angle over a `[[fields]]` list (on
    /// axis, weight 1, and at 3°, weight 0.5), sectors on a 4 nm band: the weighted mean of each
    /// point's lane, as the value is of the points' values; against the discrete rule's
    /// differences at 64 pupil samples ([`exact_lanes`]).
    #[test]
    fn segmented_keys_over_a_field_list() {
        let one = multiplexed_with("segmented", "channel_efficiencies = [0.1, 0.15, 0.2]");
        let text =
            format!("{}\n[[fields]]\nx_deg = 0\nweight = 1\n\n[[fields]]\nx_deg = 3\nweight = 0.5\n", one.text());
        let source = Source::from_text(text, "segmented lens over a field list written in the test", ".");
        let overrides = ["spectrum.range_nm=4", "options.pupil_samples=64", "lens.zones=\"sectors\""];
        let keys = ["lens.channels_nm[2]", "lens.channel_efficiencies[1]", "fields[1].x_deg"];
        let g = matches_the_fixed_rule(&source, &overrides, &keys, &exact_lanes);
        assert!(g.d_mean_mtf.iter().all(|d| *d != 0.0), "{g:?}");
    }

    /// The segmented lens's zones' area fractions (0.3, 0.25, 0.35: Σ a < 1, each free, the rim
    /// beyond the zones opaque) with the channels' own efficiencies (0.1, 0.15, 0.2), the stray
    /// light and read noise on a 4 nm band, concentric on axis and sectors at (2°, 1°): ln a_j
    /// moves the zones' edges from zone j on (rings' radii √c_k, wedges' angles 2π c_k), every
    /// edge pixel's area fraction by its edge's length in it, and τ by a_j η_j; against the
    /// discrete rule's differences at 64 pupil samples ([`exact_lanes`]).
    #[test]
    fn segmented_area_fractions_match_the_fixed_rule() {
        let source = multiplexed_with(
            "segmented",
            "channel_efficiencies = [0.1, 0.15, 0.2]\narea_fractions = [0.3, 0.25, 0.35]",
        );
        let keys = ["lens.area_fractions[0]", "lens.area_fractions[2]", "lens.f_number"];
        for at in
            [&["lens.zones=\"concentric\""][..], &["lens.zones=\"sectors\"", "field.x_deg=2", "field.y_deg=1"][..]]
        {
            let mut overrides = vec![
                "spectrum.range_nm=4",
                "options.pupil_samples=64",
                "options.glare=\"included\"",
                "camera.read_noise_e=2",
            ];
            overrides.extend(at);
            let g = matches_the_fixed_rule(&source, &overrides, &keys, &exact_lanes);
            // the zones' edges move the OTF, their areas N
            assert!(g.d_mean_mtf[..2].iter().chain(&g.d_photoelectrons[..2]).all(|d| *d != 0.0), "{g:?}");
        }
    }

    /// Where the area fractions fill the aperture (0.3, 0.3, 0.4: Σ a = 1) the last zone absorbs
    /// a fraction's change, its outer edge held on the rim: the gradient of `area_fractions[j]`
    /// against Richardson central differences (steps 4e-6 and 2e-6 of a_j) of evaluations with
    /// a_j and a_3 = 1 − a_1 − a_2 moved together, on the same fixed sampling (64 pupil samples,
    /// 4 nm band, read noise), concentric and sectors, within 1e-8 of each quantity's norm; the
    /// last fraction itself is refused there (its growth would leave the aperture).
    #[test]
    fn segmented_filled_area_fractions_let_the_last_absorb() {
        let source = multiplexed_with("segmented", "channel_efficiencies = [0.1, 0.15, 0.2]");
        let base = [0.3, 0.3, 0.4];
        let keys = ["lens.area_fractions[0]", "lens.area_fractions[1]"];
        for zones in ["lens.zones=\"concentric\"", "lens.zones=\"sectors\""] {
            let overrides = ["spectrum.range_nm=4", "options.pupil_samples=64", "camera.read_noise_e=2", zones];
            let mut set = owned(&overrides);
            set.push("lens.area_fractions=[0.3, 0.3, 0.4]".to_owned());
            let g = gradient(&source, &set, &owned(&keys)).unwrap();
            let at = |j: usize, d: f64| -> [f64; 4] {
                let mut a = base;
                a[j] += d;
                a[2] -= d;
                let mut set = owned(&overrides);
                set.push(format!("lens.area_fractions=[{:e}, {:e}, {:e}]", a[0], a[1], a[2]));
                let e = metric::evaluate(&scene::build_from(&source, &set).unwrap()).unwrap();
                [e.asnr, e.mean_mtf, e.snr0, e.photoelectrons]
            };
            let central = |j: usize, h: f64| -> [f64; 4] {
                let (up, down) = (at(j, h), at(j, -h));
                std::array::from_fn(|q| (up[q] - down[q]) / (2.0 * h))
            };
            let ours = [&g.d_asnr, &g.d_mean_mtf, &g.d_snr0, &g.d_photoelectrons];
            let references: Vec<[f64; 4]> = (0..keys.len())
                .map(|j| {
                    let h = 2e-6 * base[j];
                    let (coarse, fine) = (central(j, 2.0 * h), central(j, h));
                    std::array::from_fn(|q| (4.0 * fine[q] - coarse[q]) / 3.0)
                })
                .collect();
            for (q, name) in ["ASNR", "mean MTF", "SNR0", "N"].iter().enumerate() {
                let norm = ours[q].iter().map(|x| x * x).sum::<f64>().sqrt();
                assert!(norm > 0.0, "{name}: {g:?}");
                for (j, k) in keys.iter().enumerate() {
                    let error = (ours[q][j] - references[j][q]).abs() / norm;
                    println!(
                        "{zones} {name} {k}: gradient {:.9e}, differences {:.9e}, error/norm {error:.1e}",
                        ours[q][j], references[j][q]
                    );
                    assert!(error < 1e-8, "{zones} {name} {k}: {} vs {}", ours[q][j], references[j][q]);
                }
            }
            let e = gradient(&source, &set, &owned(&["lens.area_fractions[2]"])).unwrap_err().to_string();
            assert!(e.contains("--wrt lens.area_fractions[2]") && e.contains("fill the aperture"), "{e}");
        }
    }

    /// The keys refused, each naming itself and why: the segmented layout's channel wavelength
    /// with the other channels as background (the band edges move with it), a channel's own
    /// efficiency at 0, and the last zone's area where the zones fill the aperture.
    #[test]
    fn multiplexed_refusals_name_the_key_and_why() {
        let segmented = multiplexed("segmented");
        // a channel's wavelength where the band edges move with it
        let background = owned(&["lens.other_channels=\"background\""]);
        let e = gradient(&segmented, &background, &owned(&["lens.channels_nm[1]"])).unwrap_err().to_string();
        assert!(e.contains("--wrt lens.channels_nm[1]") && e.contains("band edges"), "{e}");
        // the last zone's area fraction where the zones fill the aperture
        let with_areas = owned(&["lens.area_fractions=[0.3, 0.3, 0.4]"]);
        let e = gradient(&segmented, &with_areas, &owned(&["lens.area_fractions[2]"])).unwrap_err().to_string();
        assert!(e.contains("--wrt lens.area_fractions[2]") && e.contains("fill the aperture"), "{e}");
        // an interleaved lens's channel under a line off axis: not on the band's exact 1-D engine
        let interleaved = multiplexed("interleaved");
        let line = owned(&["field.x_deg=1", "spectrum.shape=\"line\""]);
        let e = gradient(&interleaved, &line, &owned(&["lens.channels_nm[0]"])).unwrap_err().to_string();
        assert!(e.contains("--wrt lens.channels_nm[0]") && e.contains("a line spectrum"), "{e}");
        // a channel's own efficiency at 0, lit: √η has no derivative there
        let own = multiplexed_with("segmented", "channel_efficiencies = [0.1, 0.0, 0.2]");
        let cheap = owned(&["spectrum.range_nm=4", "options.pupil_samples=64"]);
        let e = gradient(&own, &cheap, &owned(&["lens.channel_efficiencies[1]"])).unwrap_err().to_string();
        assert!(e.contains("--wrt lens.channel_efficiencies[1]") && e.contains("√η"), "{e}");
    }
}
