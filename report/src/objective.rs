//! What `asnr optimize` maximizes and `asnr tolerance` samples: the ASNR of a scene with some of
//! its keys set, in one of four forms ([`Objective`]), and the nominal value of a scene key.
//!
//! A point is the scene of a [`Source`] with its overrides and then `key = value` for each
//! varied key ([`scene::sweep::assignment`], the `--set` text `asnr sweep` writes), evaluated by
//! `metric::evaluate`: the same scene, and so the same numbers, as `asnr evaluate --set …`.

use anyhow::{Context, Result, anyhow, bail};
use serde::Serialize;

use scene::Source;
use scene::sweep::assignment;

/// The merit a design search maximizes.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Objective {
    /// The scene's ASNR (paper eq. 1, with the scene's options).
    Asnr,
    /// The ASNR with the shot noise of all transmitted light, imaged or stray (paper SI eq. S14:
    /// `options.glare = "included"`).
    AsnrGlare,
    /// The weighted mean of the ASNR over the scene's `[[fields]]` (the scene's own average;
    /// refused for a scene of one field point).
    FovMean,
    /// The lowest ASNR over a multiplexed lens's channels, the spectrum centred at each channel's
    /// wavelength (as `asnr compare` does per channel).
    WorstChannel,
    /// The Shannon information capacity per pixel, bits (`metric::metrics`: a flat object of
    /// contrast 1, Fellgett–Linfoot over the Nyquist square).
    Capacity,
    /// The ideal observer's detectability d′ of a disk (`metric::metrics`).
    Detectability(metric::DiskTask),
}

/// The objectives as `--objective` takes them.
pub const OBJECTIVES: &str = "asnr (the scene's ASNR), asnr_glare (the glare-inclusive ASNR, SI eq. S14), fov_mean (the mean over the scene's [[fields]]) worst_channel (the lowest over a multiplexed lens's channels), capacity (the information capacity per pixel, bits, of a flat object of contrast 1) or detectability:disk:DIAMETER_UM:CONTRAST (an ideal observer's d′ of that disk)";

impl Objective {
    /// Parses an `--objective` name.
    pub fn parse(name: &str) -> Result<Objective> {
        Ok(match name.trim() {
            "asnr" => Objective::Asnr,
            "asnr_glare" => Objective::AsnrGlare,
            "fov_mean" => Objective::FovMean,
            "worst_channel" => Objective::WorstChannel,
            "capacity" => Objective::Capacity,
            "detectability" => bail!(
                "--objective detectability: name the task, detectability:disk:DIAMETER_UM:CONTRAST (e.g. detectability:disk:20:0.05)"
            ),
            other => match other.strip_prefix("detectability:") {
                Some(task) => Objective::Detectability(crate::metrics::parse_task(task)?),
                None => bail!("--objective {other}: expected {OBJECTIVES}"),
            },
        })
    }

    /// Its `--objective` name.
    pub fn name(self) -> &'static str {
        match self {
            Objective::Asnr => "asnr",
            Objective::AsnrGlare => "asnr_glare",
            Objective::FovMean => "fov_mean",
            Objective::WorstChannel => "worst_channel",
            Objective::Capacity => "capacity",
            Objective::Detectability(_) => "detectability",
        }
    }

    /// How a report names its value.
    pub fn label(self) -> &'static str {
        match self {
            Objective::Asnr => "ASNR",
            Objective::AsnrGlare => "glare-inclusive ASNR (SI eq. S14)",
            Objective::FovMean => "field-of-view mean ASNR",
            Objective::WorstChannel => "worst-channel ASNR",
            Objective::Capacity => "information capacity (bits/pixel)",
            Objective::Detectability(_) => "detectability d′",
        }
    }
}

/// The objective at one point, and whether the Fraunhofer model holds there (paper SI eq. S15;
/// for the worst channel: at every channel).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Value {
    /// The objective.
    pub value: f64,
    /// Whether the Fraunhofer model is valid there.
    pub fraunhofer_valid: bool,
}

/// The override that makes the ASNR glare-inclusive.
const GLARE_INCLUDED: &str = "options.glare=\"included\"";

/// A scene whose objective is evaluated at points: its source, its overrides, the objective.
#[derive(Clone, Debug)]
pub struct Target {
    source: Source,
    overrides: Vec<String>,
    objective: Objective,
}

/// Whether an override `key=value` sets `key`.
fn sets(overrides: &[String], key: &str) -> bool {
    overrides.iter().any(|o| o.split_once('=').is_some_and(|(k, _)| k.trim() == key))
}

impl Target {
    /// The target, checked: the scene builds with `overrides`; the keys the objective sets
    /// itself (`options.glare` for `asnr_glare`, `spectrum.center_nm` for `worst_channel`) are
    /// neither overridden nor among `keys`; `fov_mean` has `[[fields]]` and `worst_channel` a
    /// multiplexed lens's channels.
    pub fn new(source: Source, overrides: Vec<String>, objective: Objective, keys: &[String]) -> Result<Target> {
        let own = match objective {
            Objective::AsnrGlare => Some("options.glare"),
            Objective::WorstChannel => Some("spectrum.center_nm"),
            Objective::Asnr | Objective::FovMean | Objective::Capacity | Objective::Detectability(_) => None,
        };
        if let Some(own) = own
            && (sets(&overrides, own) || keys.iter().any(|k| k == own))
        {
            bail!(
                "--objective {}: it sets {own} itself, which is also given (--set, or a varied key): give one of them",
                objective.name()
            );
        }
        let built = scene::build_from(&source, &overrides)?;
        match objective {
            Objective::FovMean if built.fields().is_empty() => bail!(
                "--objective fov_mean: {} has a single field point; the field-of-view mean needs [[fields]] (or use --objective asnr)",
                source.label()
            ),
            Objective::WorstChannel if channels_nm(&source, &overrides)?.is_empty() => bail!(
                "--objective worst_channel: the lens of {} has no channels; it needs lens.model = \"multiplexed\" with lens.channels_nm",
                source.label()
            ),
            _ => {}
        }
        Ok(Target { source, overrides, objective })
    }

    /// The objective.
    pub fn objective(&self) -> Objective {
        self.objective
    }

    /// The scene's source.
    pub fn source(&self) -> &Source {
        &self.source
    }

    /// The overrides before the varied keys.
    pub fn overrides(&self) -> &[String] {
        &self.overrides
    }

    /// The objective with `keys[i] = values[i]` after the overrides (none: the scene as given).
    pub fn value(&self, keys: &[String], values: &[f64]) -> Result<Value> {
        let mut set = self.overrides.clone();
        set.extend(keys.iter().zip(values).map(|(k, v)| assignment(k, *v)));
        let at = || {
            let pairs: Vec<String> = keys.iter().zip(values).map(|(k, v)| format!("{k}={v}")).collect();
            if pairs.is_empty() { "at the scene as given".to_owned() } else { format!("at {}", pairs.join(", ")) }
        };
        match self.objective {
            Objective::Asnr | Objective::FovMean => self.evaluate(&set),
            Objective::Capacity | Objective::Detectability(_) => self.metric(&set),
            Objective::AsnrGlare => {
                set.push(GLARE_INCLUDED.to_owned());
                self.evaluate(&set)
            }
            Objective::WorstChannel => {
                let channels = channels_nm(&self.source, &set)?;
                let mut worst = Value { value: f64::INFINITY, fraunhofer_valid: true };
                for c in channels {
                    let mut at_channel = set.clone();
                    at_channel.push(assignment("spectrum.center_nm", c));
                    let v = self.evaluate(&at_channel).with_context(|| format!("channel {c} nm"))?;
                    worst.value = worst.value.min(v.value);
                    worst.fraunhofer_valid &= v.fraunhofer_valid;
                }
                Ok(worst)
            }
        }
        .with_context(at)
    }

    /// The capacity or d′ of the scene with `set` (`metric::metrics` on its evaluation).
    fn metric(&self, set: &[String]) -> Result<Value> {
        let built = scene::build_from(&self.source, set)?;
        let r = metric::evaluate(&built).map_err(|e| anyhow!("{}: {e}", self.source.label()))?;
        let task = match self.objective {
            Objective::Detectability(task) => Some(task),
            _ => None,
        };
        let options = metric::MetricsOptions { task, points: 2, ..metric::MetricsOptions::default() };
        let m = metric::metrics(&built, &r, &options).map_err(|e| anyhow!("{}: {e}", self.source.label()))?;
        let value = match &m.detectability {
            Some(d) => d.d_prime,
            None => m.capacity_bits_per_pixel,
        };
        Ok(Value { value, fraunhofer_valid: r.fraunhofer.valid })
    }

    /// The objective with `keys[i] = values[i]` after the overrides, and its gradient with
    /// respect to `keys` (each in its own units; `∂/∂keys[i]`), from the engines
    /// ([`crate::gradient::gradient`]; docs/physics.md, "Gradients"). `asnr`, `asnr_glare` and
    /// `fov_mean` are smooth; `worst_channel`, a minimum over channels, is refused.
    pub fn value_and_gradient(&self, keys: &[String], values: &[f64]) -> Result<(Value, Vec<f64>)> {
        if self.objective == Objective::WorstChannel {
            bail!(
                "--objective worst_channel: a minimum over channels has no gradient where two channels tie; use asnr, asnr_glare or fov_mean with a gradient"
            );
        }
        if matches!(self.objective, Objective::Capacity | Objective::Detectability(_)) {
            bail!(
                "--objective {}: its gradient is not computed yet; use asnr, asnr_glare or fov_mean with a gradient",
                self.objective.name()
            );
        }
        if keys.len() != values.len() {
            bail!("{} keys but {} values", keys.len(), values.len());
        }
        let mut set = self.overrides.clone();
        set.extend(keys.iter().zip(values).map(|(k, v)| assignment(k, *v)));
        if self.objective == Objective::AsnrGlare {
            set.push(GLARE_INCLUDED.to_owned());
        }
        let (g, evaluation) = crate::gradient::gradient_and_evaluation(&self.source, &set, keys)?;
        if g.keys.len() != keys.len() {
            bail!(
                "the keys {} expand to {} entries: give each list entry as its own key (lens.binary2[0], …)",
                keys.join(", "),
                g.keys.len()
            );
        }
        Ok((Value { value: g.asnr, fraunhofer_valid: evaluation.fraunhofer.valid }, g.d_asnr))
    }

    fn evaluate(&self, set: &[String]) -> Result<Value> {
        let built = scene::build_from(&self.source, set)?;
        let r = metric::evaluate(&built).map_err(|e| anyhow!("{}: {e}", self.source.label()))?;
        Ok(Value { value: r.asnr, fraunhofer_valid: r.fraunhofer.valid })
    }
}

/// A multiplexed lens's channel wavelengths, nm (empty for another lens), as the resolved scene
/// (`asnr scene`) lists them.
fn channels_nm(source: &Source, overrides: &[String]) -> Result<Vec<f64>> {
    let resolved = resolved(source, overrides)?;
    let Some(list) = resolved.get("lens").and_then(|l| l.get("channels_nm")).and_then(toml::Value::as_array) else {
        return Ok(Vec::new());
    };
    Ok(list.iter().filter_map(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64))).collect())
}

/// The scene with every default filled in, as a TOML table (validated: built once, as
/// `scene::resolved_toml` builds it).
pub(crate) fn resolved(source: &Source, overrides: &[String]) -> Result<toml::Table> {
    Ok(resolved_and_built(source, overrides)?.0)
}

/// [`resolved`] and the scene it validated, built once ([`scene::resolved_and_built`]: the
/// scene is `scene::build_from`'s).
pub(crate) fn resolved_and_built(source: &Source, overrides: &[String]) -> Result<(toml::Table, metric::Scene)> {
    let (resolved, built) = scene::resolved_and_built(source, overrides)?;
    let table = resolved
        .toml
        .parse::<toml::Table>()
        .map_err(|e| anyhow!("internal error: the resolved scene is not TOML: {e}"))?;
    Ok((table, built))
}

/// The value of the numeric key `key` (dotted, `lens.binary2[2]` for a list's entry) in the
/// scene with `overrides`, every default filled in (`asnr scene`): refused, naming the key, when
/// the scene has no such key or its value is not a number.
pub fn number_at(source: &Source, overrides: &[String], key: &str) -> Result<f64> {
    let table = resolved(source, overrides)?;
    let missing = || anyhow!("{key}: {} has no such key (`asnr scene` lists its keys)", source.label());
    let mut cursor = &toml::Value::Table(table);
    for part in key.split('.') {
        let (name, index) = match part.split_once('[') {
            Some((name, rest)) => {
                let index: usize = rest
                    .strip_suffix(']')
                    .and_then(|i| i.trim().parse().ok())
                    .with_context(|| format!("{key}: `{part}` is not a key or a list entry (e.g. lens.binary2[1])"))?;
                (name, Some(index))
            }
            None => (part, None),
        };
        cursor = cursor.get(name).ok_or_else(missing)?;
        if let Some(i) = index {
            let list = cursor.as_array().ok_or_else(|| anyhow!("{key}: `{name}` is not a list"))?;
            cursor = list.get(i).ok_or_else(|| anyhow!("{key}: `{name}` has {} entries", list.len()))?;
        }
    }
    match cursor {
        toml::Value::Float(v) => Ok(*v),
        toml::Value::Integer(v) => Ok(*v as f64),
        other => bail!("{key} = {other}: not a number; only numeric keys can be varied"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The metric objectives by name; detectability without its task is refused with the form.
    #[test]
    fn metric_objectives_parse() {
        assert_eq!(Objective::parse("capacity").unwrap(), Objective::Capacity);
        match Objective::parse("detectability:disk:20:0.05").unwrap() {
            Objective::Detectability(t) => assert!((t.diameter_m - 20e-6).abs() < 1e-18 && t.contrast == 0.05),
            other => panic!("{other:?}"),
        }
        let e = Objective::parse("detectability").unwrap_err().to_string();
        assert!(e.contains("detectability:disk:DIAMETER_UM:CONTRAST"), "{e}");
    }

    #[test]
    fn objectives_parse_and_refuse_unknown_names() {
        for o in [Objective::Asnr, Objective::AsnrGlare, Objective::FovMean, Objective::WorstChannel] {
            assert_eq!(Objective::parse(o.name()).unwrap(), o);
        }
        let e = Objective::parse("sharpness").unwrap_err().to_string();
        assert!(e.contains("--objective sharpness: expected asnr"), "{e}");
    }

    #[test]
    fn the_nominal_value_of_a_key_and_its_refusals() {
        let source = scene::read(None).unwrap();
        assert_eq!(number_at(&source, &[], "lens.f_number").unwrap(), 2.5);
        assert_eq!(number_at(&source, &["spectrum.range_nm=20".to_owned()], "spectrum.range_nm").unwrap(), 20.0);
        let e = number_at(&source, &[], "lens.colour").unwrap_err().to_string();
        assert!(e.contains("lens.colour: embedded paper scene has no such key"), "{e}");
        let e = number_at(&source, &[], "lens.model").unwrap_err().to_string();
        assert!(e.contains("lens.model = \"chromatic\": not a number"), "{e}");
    }

    /// The glare-inclusive objective is `asnr evaluate --set options.glare="included"`'s ASNR,
    /// and refuses a scene that sets the glare itself.
    #[test]
    fn the_glare_objective_is_the_glare_inclusive_evaluation() {
        let source = scene::read(None).unwrap();
        let target = Target::new(source.clone(), Vec::new(), Objective::AsnrGlare, &[]).unwrap();
        let v = target.value(&[], &[]).unwrap().value;
        let direct = metric::evaluate(&scene::build_from(&source, &[GLARE_INCLUDED.to_owned()]).unwrap()).unwrap();
        assert_eq!(v, direct.asnr);
        let plain = Target::new(source.clone(), Vec::new(), Objective::Asnr, &[]).unwrap();
        assert!(plain.value(&[], &[]).unwrap().value > v);
        let e =
            Target::new(source.clone(), vec!["options.glare=\"first_order\"".to_owned()], Objective::AsnrGlare, &[])
                .unwrap_err()
                .to_string();
        assert!(e.contains("sets options.glare itself"), "{e}");
        let e = Target::new(source.clone(), Vec::new(), Objective::FovMean, &[]).unwrap_err().to_string();
        assert!(e.contains("single field point"), "{e}");
        let e = Target::new(source, Vec::new(), Objective::WorstChannel, &[]).unwrap_err().to_string();
        assert!(e.contains("has no channels"), "{e}");
    }

    /// `value_and_gradient` of the field-of-view mean and of the glare-inclusive ASNR against
    /// central differences of `value` at tolerance 1e-10 (step (3e-10)^{1/3} of the value,
    /// docs/physics.md, "Gradients"), within 10× the 1e-6 asked relative to the gradient's
    /// norm; the worst channel is refused.
    #[test]
    fn value_and_gradient_match_differences_of_the_value() {
        let paper = scene::read(None).unwrap();
        let text = format!("{}\n[[fields]]\nx_deg = 0.0\n\n[[fields]]\nx_deg = 4.0\nweight = 0.5\n", paper.text());
        let fields = Source::from_text(text, "fields", ".");
        let keys: Vec<String> = ["exposure.time_ms", "camera.pixel_pitch_um"].map(str::to_owned).to_vec();
        for (source, objective) in [(fields, Objective::FovMean), (paper.clone(), Objective::AsnrGlare)] {
            let values: Vec<f64> = keys.iter().map(|k| number_at(&source, &[], k).unwrap()).collect();
            let target = Target::new(source.clone(), Vec::new(), objective, &keys).unwrap();
            let (value, gradient) = target.value_and_gradient(&keys, &values).unwrap();
            assert_eq!(value.value, target.value(&keys, &values).unwrap().value);
            let converged = Target::new(source, vec!["options.tolerance=1e-10".to_owned()], objective, &keys).unwrap();
            let norm = gradient.iter().zip(&values).map(|(g, v)| (g * v).powi(2)).sum::<f64>().sqrt();
            for i in 0..keys.len() {
                let h = 3e-10_f64.cbrt() * values[i];
                let at = |x: f64| {
                    let mut v = values.clone();
                    v[i] = x;
                    converged.value(&keys, &v).unwrap().value
                };
                let reference = (at(values[i] + h) - at(values[i] - h)) / (2.0 * h);
                let error = (gradient[i] - reference).abs() * values[i];
                assert!(error <= 1e-5 * norm, "{objective:?} {}: {} vs {reference}", keys[i], gradient[i]);
            }
        }
        let e = Target::new(paper, Vec::new(), Objective::Asnr, &[])
            .map(|t| Target { objective: Objective::WorstChannel, ..t })
            .unwrap()
            .value_and_gradient(&keys, &[1.0, 5.0])
            .unwrap_err()
            .to_string();
        assert!(e.contains("worst_channel"), "{e}");
    }

    /// The worst channel of an interleaved multiplexed lens is the lowest of the three
    /// evaluations with the spectrum centred at each channel (as `asnr evaluate --set
    /// spectrum.center_nm=…` gives them), and the search may not set the centre itself.
    #[test]
    fn the_worst_channel_is_the_lowest_channel_evaluation() {
        let paper = scene::read(None).unwrap();
        let text = paper.text();
        let lens_at = text.find("[lens]").unwrap();
        let rest = &text[text[lens_at..].find("\n[").map(|i| lens_at + i).unwrap()..];
        let lens = "[lens]\nmodel = \"multiplexed\"\nlayout = \"interleaved\"\nf_number = 2.5\nfocal_length_mm = 3.36\nchannels_nm = [750.0, 800.0, 850.0]\nefficiency = 0.15\ntransmission = 0.55\n";
        let source = Source::from_text(format!("{lens}{rest}"), "multiplexed", ".");
        let target = Target::new(source.clone(), Vec::new(), Objective::WorstChannel, &[]).unwrap();
        let worst = target.value(&[], &[]).unwrap().value;
        let each: Vec<f64> = [750, 800, 850]
            .iter()
            .map(|c| {
                let built = scene::build_from(&source, &[format!("spectrum.center_nm={c}")]).unwrap();
                metric::evaluate(&built).unwrap().asnr
            })
            .collect();
        assert_eq!(worst, each.iter().copied().fold(f64::INFINITY, f64::min), "{each:?}");
        let e = Target::new(source, Vec::new(), Objective::WorstChannel, &["spectrum.center_nm".to_owned()])
            .unwrap_err()
            .to_string();
        assert!(e.contains("sets spectrum.center_nm itself"), "{e}");
    }
}
