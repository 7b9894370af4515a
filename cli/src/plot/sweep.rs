//! The chart of `asnr sweep --plot`: a line over one key, a heatmap with its ridge over two.

use super::*;

/// Writes a sweep's ASNR: a line against the key for one swept key, a heatmap with the ridge of
/// the optimum (the best second key for each value of the first) for two. An empty `title` is
/// none.
pub fn sweep_plot(path: &Path, figure: &Figure, title: &str, ranges: &[Range], points: &[Point]) -> Result<()> {
    match ranges {
        [range] => {
            let series = Series {
                label: "ASNR".to_owned(),
                points: points.iter().map(|p| (p.values[0], p.asnr)).collect(),
                shaded: Vec::new(),
                best: None,
            };
            let x = axis_label(&range.key);
            let unit = quantity(&range.key).1.unwrap_or_default();
            let labels = Labels { title, x: &x, y: "ASNR", x_unit: unit, ..Labels::default() };
            lines_plot("--plot", path, figure, &labels, &[series], &[], true)
        }
        [first, second] => {
            let grid = Grid {
                xs: crate::sweep::axis(first),
                ys: crate::sweep::axis(second),
                z: points.iter().map(|p| p.asnr).collect(),
                shaded: Vec::new(),
            };
            let (x, y) = (axis_label(&first.key), axis_label(&second.key));
            let ridge = format!("best {} for each {}", quantity(&second.key).0, quantity(&first.key).0);
            let labels = Labels { title, x: &x, y: &y, z: "ASNR", ridge: &ridge, ..Labels::default() };
            heatmap_plot("--plot", path, figure, &labels, &grid, &[])
        }
        _ => bail!("--plot: a sweep over {} keys; plots take one key (a line) or two (a heatmap)", ranges.len()),
    }
}
