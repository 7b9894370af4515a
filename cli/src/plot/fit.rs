//! Log–log panels of measured points and fitted power laws (a camera's STF and PTC).

use super::*;

/// A set of measured points on a [`FitPanel`], with the straight line fitted to them in log-log
/// coordinates.
#[derive(Clone, Debug)]
pub struct FitSet {
    /// Legend entry (the fit's slope belongs in it).
    pub label: String,
    /// Measured `(x, y)`, both > 0 (others are left out).
    pub points: Vec<(f64, f64)>,
    /// Per point, whether the fit used it: drawn filled, the others hollow.
    pub fitted: Vec<bool>,
    /// `log10 y = intercept + slope · log10 x`: (slope, intercept), drawn over the fitted points.
    pub line: Option<(f64, f64)>,
    /// Colour index into the palette.
    pub colour: usize,
}

/// One log-log panel of measured points and fitted power laws (a camera's STF or PTC).
#[derive(Clone, Debug)]
pub struct FitPanel<'a> {
    /// Caption above the panel, e.g. "(a) signal transfer".
    pub caption: &'a str,
    /// Description of the x axis, with its unit.
    pub x: &'a str,
    /// Description of the y axis, with its unit.
    pub y: &'a str,
    /// The point sets.
    pub sets: Vec<FitSet>,
}

/// Writes `panels` side by side on log-log axes, each set's points (filled where fitted, hollow
/// where not) and fitted line, one legend below for all; SVG or PNG by the file's extension;
/// errors name `flag`.
pub fn fit_panels_plot(flag: &str, path: &Path, figure: &Figure, title: &str, panels: &[FitPanel]) -> Result<()> {
    if panels.iter().all(|p| p.sets.iter().all(|s| s.points.iter().all(|&(x, y)| !(x > 0.0 && y > 0.0)))) {
        bail!("{flag} {}: nothing to plot (no positive points)", path.display());
    }
    render(flag, path, figure, &FitPlot { title, panels })
}

/// The panels of [`fit_panels_plot`].
pub(super) struct FitPlot<'a> {
    pub(super) title: &'a str,
    pub(super) panels: &'a [FitPanel<'a>],
}

impl FitPlot<'_> {
    pub(super) fn stroke(set: &FitSet) -> Stroke {
        Stroke::solid(PALETTE[set.colour % PALETTE.len()], 1.3)
    }
}

impl Plot for FitPlot<'_> {
    fn title(&self) -> &str {
        self.title
    }

    fn entries(&self) -> Vec<Entry> {
        let mut entries = Vec::new();
        for set in self.panels.iter().flat_map(|p| &p.sets) {
            if !entries.iter().any(|e: &Entry| e.label == set.label) {
                let stroke = Self::stroke(set);
                entries.push(Entry { label: set.label.clone(), swatch: Swatch::Dot(stroke, stroke.colour) });
            }
        }
        if self.panels.iter().flat_map(|p| &p.sets).any(|s| s.fitted.iter().any(|f| !f)) {
            entries.push(Entry {
                label: "hollow: levels left out of the fits (dark-limited, or at or near saturation)".to_owned(),
                swatch: Swatch::Ring(RGBColor(90, 90, 90)),
            });
        }
        entries
    }

    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>, ctx: Ctx) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        let cells = area.split_evenly((1, self.panels.len().max(1)));
        for (panel, cell) in self.panels.iter().zip(&cells) {
            let caption_h = ctx.px(DESC_PT * 1.8);
            let (top, below) = cell.split_vertically(caption_h);
            let (cw, _) = top.dim_in_pixel();
            let style = ctx.font(DESC_PT).color(&INK).pos(Pos::new(HPos::Center, VPos::Top));
            let centre = i32::try_from(cw / 2).unwrap_or(0);
            top.draw(&Text::new(panel.caption.to_owned(), (centre, ctx.px(2.0)), style)).map_err(|e| fail(&e))?;
            let log = |&(x, y): &(f64, f64)| (x > 0.0 && y > 0.0).then(|| (x.log10(), y.log10()));
            let all: Vec<(f64, f64)> = panel.sets.iter().flat_map(|s| s.points.iter().filter_map(log)).collect();
            if all.is_empty() {
                continue;
            }
            // whole decades around the data, or 5 % of the span beyond it where that is tighter
            let around = |(lo, hi): (f64, f64)| {
                let pad = 0.05 * (hi - lo).max(1.0);
                ((lo - pad).max(lo.floor()), (hi + pad).min(hi.ceil().max(hi + 1e-9)))
            };
            let x = around(extent(all.iter().map(|p| p.0)));
            let y = around(extent(all.iter().map(|p| p.1)));
            let axes = Axes { x, y, x_desc: panel.x, y_desc: panel.y, grid: true, y_log: true, x_log: true };
            let (mut chart, _) = axes.build(&below, ctx, 0)?;
            axes.label_between_decades(&below, &chart, ctx)?;
            minor_decades(&mut chart, ctx, x, y, (true, true))?;
            for set in &panel.sets {
                let stroke = Self::stroke(set);
                let points: Vec<((f64, f64), bool)> = set
                    .points
                    .iter()
                    .zip(set.fitted.iter().chain(std::iter::repeat(&true)))
                    .filter_map(|(p, &f)| log(p).map(|p| (p, f)))
                    .collect();
                if let Some((slope, intercept)) = set.line {
                    let fitted = || points.iter().filter(|(_, f)| *f).map(|(p, _)| p.0);
                    let (lo, hi) = (fitted().fold(f64::INFINITY, f64::min), fitted().fold(f64::NEG_INFINITY, f64::max));
                    if lo < hi {
                        // the line over the fitted points and a little beyond, inside the axes
                        let (a, b) = ((lo - 0.15 * (hi - lo)).max(x.0), (hi + 0.15 * (hi - lo)).min(x.1));
                        let line: Vec<(f64, f64)> = (0..=64)
                            .map(|i| a + (b - a) * f64::from(i) / 64.0)
                            .map(|v| (v, intercept + slope * v))
                            .filter(|p| p.1 >= y.0 && p.1 <= y.1)
                            .collect();
                        draw_curve(&mut chart, ctx, &line, stroke)?;
                    }
                }
                let r = ctx.px(2.6);
                for &(p, fitted) in &points {
                    if fitted {
                        chart
                            .draw_series([
                                Circle::new(p, r, stroke.colour.filled()),
                                Circle::new(p, r, WHITE.stroke_width(ctx.stroke(0.5))),
                            ])
                            .map_err(|e| fail(&e))?;
                    } else {
                        chart
                            .draw_series([
                                Circle::new(p, r, WHITE.filled()),
                                Circle::new(p, r, stroke.colour.stroke_width(ctx.stroke(1.0))),
                            ])
                            .map_err(|e| fail(&e))?;
                    }
                }
            }
            axes.frame(&mut chart, ctx)?;
        }
        Ok(())
    }
}
