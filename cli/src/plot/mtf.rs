//! The MTF chart of `asnr mtf --plot`: the polychromatic MTF, the monochromatic curves, the
//! diffraction limit and Nyquist, and where the OTF depends on direction (off axis with lateral
//! colour, a 2-D pupil: a phase map, non-radial Zernike terms, a decentred iris) the tangential
//! and sagittal curves beside their mean — over azimuth for a 2-D pupil — for the single field
//! point, or for each point of a field-of-view average (up to four), labelled with the point's
//! field angles in degrees; frequencies in cycles/mm.

use super::*;

/// Writes the MTF curve as a line chart, SVG or PNG by the file's extension: the polychromatic
/// MTF, the off-axis directional MTFs, the monochromatic curves, and on top the diffraction limit
/// and the Nyquist frequency (when the axis extends past it). An empty `title` is none.
pub fn mtf_plot(path: &Path, figure: &Figure, title: &str, curve: &MtfCurve) -> Result<()> {
    render("--plot", path, figure, &MtfPlot { title, curve })
}

/// The MTF chart of `asnr mtf --plot`.
pub(super) struct MtfPlot<'a> {
    pub(super) title: &'a str,
    pub(super) curve: &'a MtfCurve,
}

/// The polychromatic MTF.
pub(super) const POLY: Stroke = Stroke::solid(RGBColor(20, 80, 200), 1.8);
/// Monochromatic curves: thin, in colours apart from the polychromatic blue.
pub(super) const MONO: [RGBColor; 5] = [
    RGBColor(235, 140, 0),
    RGBColor(40, 160, 70),
    RGBColor(170, 60, 170),
    RGBColor(215, 40, 40),
    RGBColor(0, 150, 160),
];
/// The off-axis directional MTFs: along the field, across it.
pub(super) const OFF_AXIS: [Stroke; 2] =
    [Stroke::dashed(RGBColor(90, 160, 240), 1.3, 5.0, 2.0), Stroke::dashed(RGBColor(10, 30, 110), 1.3, 2.0, 1.5)];

/// The directional MTFs of a single field's `curve` (frequencies along the field direction, then
/// across it; on axis along x, then y) with their legend labels; `None` where the OTF does not
/// depend on direction. The only place that names the directional fields.
pub(super) fn off_axis(curve: &MtfCurve) -> Option<[(&[f64], &'static str); 2]> {
    let [t, s] = direction_names(curve.field_deg);
    Some([(curve.mtf_tangential.as_deref()?, t), (curve.mtf_sagittal.as_deref()?, s)])
}

/// The two directions' names at a field point: along x and along y on axis (where no direction
/// is the field's, as the text table says), else tangential and sagittal.
fn direction_names(field_deg: [f64; 2]) -> [&'static str; 2] {
    if field_deg == [0.0, 0.0] {
        ["along x", "along y"]
    } else {
        ["tangential (along the field)", "sagittal (across the field)"]
    }
}

/// At most this many field points of a field-of-view average get their own directional curves
/// (three each); beyond, the weighted means' are drawn, as for a single field (`--csv` and
/// `--json` carry every point's).
const FIELD_POINTS_DRAWN: usize = 4;

/// One field point's directional curves: where it is, degrees, its mean MTF and its tangential
/// and sagittal MTFs.
struct FieldDirections<'a> {
    field_deg: [f64; 2],
    mean: &'a [f64],
    tangential: &'a [f64],
    sagittal: &'a [f64],
}

/// The field points of a field-of-view average whose OTF depends on direction, each drawn with
/// its own three curves; empty for a single field (drawn by [`off_axis`] beside the headline
/// curve) and above [`FIELD_POINTS_DRAWN`] points.
fn field_directions(curve: &MtfCurve) -> Vec<FieldDirections<'_>> {
    if curve.field_points.len() > FIELD_POINTS_DRAWN {
        return Vec::new();
    }
    curve
        .field_points
        .iter()
        .filter_map(|p| {
            Some(FieldDirections {
                field_deg: p.field_deg,
                mean: &p.mtf,
                tangential: p.mtf_tangential.as_deref()?,
                sagittal: p.mtf_sagittal.as_deref()?,
            })
        })
        .collect()
}

/// A field point as the legend names it: "on axis" or "field (8°, 0°)".
fn field_name(field_deg: [f64; 2]) -> String {
    if field_deg == [0.0, 0.0] {
        "on axis".to_owned()
    } else {
        format!(
            "field ({}°, {}°)",
            number(optics::round_for_display(field_deg[0])),
            number(optics::round_for_display(field_deg[1]))
        )
    }
}

/// What the mean of the directions is: over azimuth for a sampled (2-D) pupil, else the
/// tangential–sagittal average (the curve's `mtf`, as the mean MTF is).
fn mean_name(curve: &MtfCurve) -> &'static str {
    if curve.mtf_over_azimuth { "mean over azimuth" } else { "mean of both directions" }
}

/// A field point's three strokes: its mean solid and wider, tangential dashed, sagittal dotted,
/// in the point's colour (the palette after the polychromatic blue).
fn field_strokes(i: usize) -> [Stroke; 3] {
    let colour = PALETTE[(i + 1) % PALETTE.len()];
    [Stroke::solid(colour, 1.6), Stroke::dashed(colour, 1.1, 5.0, 2.0), Stroke::dashed(colour, 1.1, 1.5, 1.5)]
}

impl MtfPlot<'_> {
    pub(super) fn mono(i: usize) -> Stroke {
        Stroke::solid(MONO[i % MONO.len()], 0.9)
    }

    /// Whether the axis extends past Nyquist, so the Nyquist line is drawn.
    pub(super) fn nyquist(&self) -> Option<f64> {
        let x_max = self.curve.frequency_cyc_per_mm.last().copied().unwrap_or(1.0);
        let n = self.curve.nyquist_cyc_per_mm;
        (n.is_finite() && n < x_max * 0.999).then_some(n)
    }
}

impl Plot for MtfPlot<'_> {
    fn title(&self) -> &str {
        self.title
    }

    fn entries(&self) -> Vec<Entry> {
        let curve = self.curve;
        let fields = field_directions(curve);
        let poly = match (curve.field_points.len(), off_axis(curve).is_some()) {
            (0, false) => "polychromatic MTF".to_owned(),
            (0, true) if curve.mtf_over_azimuth => {
                format!("polychromatic MTF, {} ({})", mean_name(curve), field_name(curve.field_deg))
            }
            (0, true) => "polychromatic MTF (mean of both directions)".to_owned(),
            (n, _) => format!("polychromatic MTF, weighted mean of {n} field points"),
        };
        let mut entries = vec![Entry { label: poly, swatch: Swatch::Line(POLY) }];
        let single = if fields.is_empty() { off_axis(curve) } else { None };
        for ((ys, label), stroke) in single.into_iter().flatten().zip(OFF_AXIS) {
            // a directional curve on the mean (on axis in all but name): said, as the dashes
            // over the mean are all that show of it
            let apart = ys.iter().zip(&curve.mtf).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            let label = if apart < COINCIDENT {
                format!("{label}, within {:.3} of the mean", ((apart * 1e3).ceil() / 1e3).max(1e-3))
            } else {
                label.to_owned()
            };
            entries.push(Entry { label, swatch: Swatch::Line(stroke) });
        }
        for (i, f) in fields.iter().enumerate() {
            let at = field_name(f.field_deg);
            let [mean, tangential, sagittal] = field_strokes(i);
            let [t, s] = direction_names(f.field_deg);
            entries.push(Entry { label: format!("{at}: {}", mean_name(curve)), swatch: Swatch::Line(mean) });
            entries.push(Entry { label: format!("{at}: {t}"), swatch: Swatch::Line(tangential) });
            entries.push(Entry { label: format!("{at}: {s}"), swatch: Swatch::Line(sagittal) });
        }
        for (i, wl) in curve.wavelengths_nm.iter().enumerate() {
            entries.push(Entry { label: format!("{wl:.1} nm"), swatch: Swatch::Line(Self::mono(i)) });
        }
        entries.push(Entry {
            label: format!("diffraction limit ({:.1} nm)", curve.mean_wavelength_nm),
            swatch: Swatch::Line(REFERENCE),
        });
        if let Some(n) = self.nyquist() {
            entries.push(Entry { label: format!("Nyquist ({n:.1} cycles/mm)"), swatch: Swatch::Line(MARK) });
        }
        entries
    }

    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>, ctx: Ctx) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        let curve = self.curve;
        let x_max = curve.frequency_cyc_per_mm.last().copied().unwrap_or(1.0).max(1e-12);
        let y_desc = if curve.pixel_mtf { "MTF (lens × pixel)" } else { "MTF" };
        let x_desc = axis_label("frequency_cyc_per_mm");
        let axes =
            Axes { x: (0.0, x_max), y: (0.0, 1.05), x_desc: &x_desc, y_desc, grid: true, y_log: false, x_log: false };
        let (mut chart, _) = axes.build(area, ctx, 0)?;
        let xs = &curve.frequency_cyc_per_mm;
        let series = |ys: &[f64]| xs.iter().copied().zip(ys.iter().copied()).collect::<Vec<_>>();
        // the wide polychromatic line first, the thinner and dashed ones over it, so where they
        // coincide each still shows (the mean through the dashes' gaps)
        draw_curve(&mut chart, ctx, &series(&curve.mtf), POLY)?;
        for (i, ys) in curve.monochromatic.iter().enumerate() {
            draw_curve(&mut chart, ctx, &series(ys), Self::mono(i))?;
        }
        let fields = field_directions(curve);
        let single = if fields.is_empty() { off_axis(curve) } else { None };
        for ((ys, _), stroke) in single.into_iter().flatten().zip(OFF_AXIS) {
            draw_curve(&mut chart, ctx, &series(ys), stroke)?;
        }
        for (i, f) in fields.iter().enumerate() {
            for (ys, stroke) in [f.mean, f.tangential, f.sagittal].into_iter().zip(field_strokes(i)) {
                draw_curve(&mut chart, ctx, &series(ys), stroke)?;
            }
        }
        // references last, on top: the diffraction limit often coincides with the curve at the
        // design wavelength
        draw_curve(&mut chart, ctx, &series(&curve.diffraction_limited), REFERENCE)?;
        if let Some(n) = self.nyquist() {
            draw_curve(&mut chart, ctx, &[(n, 0.0), (n, 1.05)], MARK)?;
        }
        axes.frame(&mut chart, ctx)
    }
}
