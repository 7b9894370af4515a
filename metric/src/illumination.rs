//! Relative illumination: the image-plane irradiance at a field point relative to the axis
//! (docs/physics.md, "Relative illumination"). Off by default, as in the paper.

use optics::Field;
use serde::Serialize;

use crate::Error;

/// How the irradiance falls off with the field angle θ, as a factor `RI(θ) ∈ [0, 1]` on the
/// signal (paper SI eq. S7: the camera-plane irradiance) of each field point.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum RelativeIllumination {
    /// None: every field point is as bright as the axis (the paper's on-axis analysis).
    #[default]
    None,
    /// The cosine-fourth law of a thin lens imaging a Lambertian object, `RI = cos⁴θ`: the
    /// pupil seen obliquely (cos θ), the longer path to the image point (cos²θ) and the
    /// oblique incidence on the detector (cos θ).
    Cos4,
    /// The same factor at every field point.
    Constant(f64),
    /// The lens's own, against the field angle (a lens design program's relative illumination
    /// analysis): linear between the points, refused beyond them.
    Table {
        /// Where it came from (a file name), for reports.
        label: String,
        /// Field angles, radians, ≥ 0, strictly increasing.
        angles_rad: Vec<f64>,
        /// The factor at each angle, in `[0, 1]`.
        values: Vec<f64>,
    },
}

impl RelativeIllumination {
    /// A constant factor `value` in `[0, 1]`.
    pub fn constant(value: f64) -> Result<Self, Error> {
        if !(value.is_finite() && (0.0..=1.0).contains(&value)) {
            return Err(Error::OutOfRange { name: "relative illumination", value, expected: "a fraction in [0, 1]" });
        }
        Ok(RelativeIllumination::Constant(value))
    }

    /// The lens's own table: `angles_rad` (≥ 1, finite, ≥ 0, below 90°, strictly increasing) and
    /// `values` (as many, each in `[0, 1]`), `label` naming it in reports.
    pub fn table(label: impl Into<String>, angles_rad: Vec<f64>, values: Vec<f64>) -> Result<Self, Error> {
        if angles_rad.is_empty() || angles_rad.len() != values.len() {
            return Err(Error::OutOfRange {
                name: "relative illumination table length",
                value: values.len() as f64,
                expected: "at least one point, one value per field angle",
            });
        }
        for (i, &a) in angles_rad.iter().enumerate() {
            let increasing = i == 0 || a > angles_rad[i - 1];
            if !((0.0..std::f64::consts::FRAC_PI_2).contains(&a) && increasing) {
                return Err(Error::OutOfRange {
                    name: "relative illumination field angle (degrees)",
                    value: a.to_degrees(),
                    expected: "field angles from 0 to below 90°, strictly increasing",
                });
            }
        }
        for &v in &values {
            RelativeIllumination::constant(v)?;
        }
        Ok(RelativeIllumination::Table { label: label.into(), angles_rad, values })
    }

    /// The field angle θ of `field` from the axis, radians: `tan²θ = tan²θx + tan²θy` (the image
    /// point at `f0 (tan θx, tan θy)`).
    pub fn field_angle(field: Field) -> f64 {
        field.x_rad.tan().hypot(field.y_rad.tan()).atan()
    }

    /// The factor at `field`, or the error naming the angle when a table does not reach it.
    pub fn at(&self, field: Field) -> Result<f64, Error> {
        let theta = Self::field_angle(field);
        Ok(match self {
            RelativeIllumination::None => 1.0,
            // cos²θ = 1/(1 + tan²θ), exact on axis
            RelativeIllumination::Cos4 => {
                let t2 = field.x_rad.tan().powi(2) + field.y_rad.tan().powi(2);
                1.0 / ((1.0 + t2) * (1.0 + t2))
            }
            RelativeIllumination::Constant(v) => *v,
            RelativeIllumination::Table { angles_rad, values, .. } => {
                let (first, last) = (angles_rad[0], angles_rad[angles_rad.len() - 1]);
                // a table's end angles, given in degrees, may differ from θ by rounding
                let slack = 1e-12;
                if theta < first - slack || theta > last + slack {
                    return Err(Error::OutOfRange {
                        name: "field angle (degrees) for the relative illumination table",
                        value: theta.to_degrees(),
                        expected: "a field angle the table covers (it is not extrapolated)",
                    });
                }
                if angles_rad.len() == 1 {
                    return Ok(values[0]);
                }
                let theta = theta.clamp(first, last);
                let k = angles_rad.partition_point(|&a| a <= theta).clamp(1, angles_rad.len() - 1);
                let (a0, a1) = (angles_rad[k - 1], angles_rad[k]);
                let u = (theta - a0) / (a1 - a0);
                values[k - 1] + u * (values[k] - values[k - 1])
            }
        })
    }

    /// `∂ ln RI/∂θ_a` at `field` along the field angle `axis` (0: θx, 1: θy), per radian
    /// (docs/physics.md, "Gradients: the field point"), or why it has none there:
    /// - none and a constant: 0;
    /// - `cos4`: `ln RI = −2 ln(1 + tan²θx + tan²θy)`, so `−4 tan θ_a sec²θ_a/(1 + tan²θ)`;
    /// - a table, linear in θ between its points: its slope times
    ///   `∂θ/∂θ_a = tan θ_a sec²θ_a/(tan θ (1 + tan²θ))` (θ = atan √(tan²θx + tan²θy)), over RI;
    ///   refused on one of its points (a kink, or its end) and on axis, where the table read at
    ///   |θ| has a kink unless its first slope is 0 (then 0; a single point: a constant, 0).
    pub fn field_log_derivative(&self, field: Field, axis: usize) -> Result<f64, String> {
        let angle = if axis == 0 { field.x_rad } else { field.y_rad };
        let (tan, sec2) = (angle.tan(), 1.0 / (angle.cos() * angle.cos()));
        let t2 = field.x_rad.tan().powi(2) + field.y_rad.tan().powi(2);
        match self {
            RelativeIllumination::None | RelativeIllumination::Constant(_) => Ok(0.0),
            RelativeIllumination::Cos4 => Ok(-4.0 * tan * sec2 / (1.0 + t2)),
            RelativeIllumination::Table { angles_rad, values, label } => {
                if angles_rad.len() == 1 {
                    return Ok(0.0);
                }
                let theta = Self::field_angle(field);
                if t2 == 0.0 {
                    // RI(|θ|): even in each angle, smooth where the first slope is 0
                    if values[1] == values[0] {
                        return Ok(0.0);
                    }
                    return Err(format!(
                        "the relative illumination table {label} is read at the field angle |θ|, so on axis it has a \
                         kink (its first slope is not 0)"
                    ));
                }
                if let Some(a) = angles_rad.iter().find(|&&a| (theta - a).abs() <= 1e-9 * a.max(1e-3)) {
                    return Err(format!(
                        "the relative illumination table {label} is linear between its points, so it has a kink (or \
                         its end) at {}°, where the field point lies; move the field point off the table's points",
                        optics::round_for_display(a.to_degrees())
                    ));
                }
                let k = angles_rad.partition_point(|&a| a <= theta).clamp(1, angles_rad.len() - 1);
                let slope = (values[k] - values[k - 1]) / (angles_rad[k] - angles_rad[k - 1]);
                let d_theta = tan * sec2 / (t2.sqrt() * (1.0 + t2));
                let ri = self.at(field).map_err(|e| e.to_string())?;
                Ok(slope * d_theta / ri)
            }
        }
    }

    /// The scene-file spelling: `none`, `cos4`, the constant, or the table's label.
    pub fn name(&self) -> String {
        match self {
            RelativeIllumination::None => "none".to_owned(),
            RelativeIllumination::Cos4 => "cos4".to_owned(),
            RelativeIllumination::Constant(v) => format!("{v}"),
            RelativeIllumination::Table { label, .. } => label.clone(),
        }
    }

    /// What a report says of it.
    pub fn describe(&self) -> String {
        match self {
            RelativeIllumination::None => "none (every field point as bright as the axis, as in the paper)".to_owned(),
            RelativeIllumination::Cos4 => "cos⁴θ (thin lens, Lambertian object)".to_owned(),
            RelativeIllumination::Constant(v) => format!("{v} at every field point"),
            RelativeIllumination::Table { label, angles_rad, .. } => format!(
                "the lens's own, {label} ({} point{}, {}–{}°)",
                angles_rad.len(),
                if angles_rad.len() == 1 { "" } else { "s" },
                optics::round_for_display(angles_rad[0].to_degrees()),
                optics::round_for_display(angles_rad[angles_rad.len() - 1].to_degrees())
            ),
        }
    }
}

/// The relative illumination an evaluation used: which, and its factor at the field point.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct IlluminationReport {
    /// `"none"`, `"cos4"`, the constant, or the table's label (the scene-file value).
    pub model: String,
    /// What it is, in words.
    pub description: String,
    /// The factor on the signal at the field point (over a field-of-view average, the weighted
    /// mean; each point's is in `field_points`).
    pub factor: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `field_log_derivative` against central differences of `ln at` (step 1e-5 rad, truncation
    /// ~1e-10 relative): cos⁴ and a table between its points, along x and y at (12°, −7°); on
    /// axis cos⁴'s is 0; a table is refused on axis and on one of its points.
    #[test]
    fn field_log_derivative_matches_differences() {
        let table = RelativeIllumination::table(
            "ri.csv",
            [0.0, 10.0, 20.0, 30.0].iter().map(|d: &f64| d.to_radians()).collect(),
            vec![1.0, 0.97, 0.9, 0.8],
        )
        .unwrap();
        let (x, y) = (12f64.to_radians(), -7f64.to_radians());
        let h = 1e-5;
        for ri in [RelativeIllumination::Cos4, table.clone(), RelativeIllumination::Constant(0.7)] {
            for axis in 0..2 {
                let at = |d: f64| {
                    let f = if axis == 0 { Field::new(x + d, y) } else { Field::new(x, y + d) };
                    ri.at(f).unwrap().ln()
                };
                let reference = (at(h) - at(-h)) / (2.0 * h);
                let ours = ri.field_log_derivative(Field::new(x, y), axis).unwrap();
                assert!(
                    (ours - reference).abs() <= 1e-8 * reference.abs().max(1e-3),
                    "{ri:?} {axis}: {ours} {reference}"
                );
            }
        }
        assert_eq!(RelativeIllumination::Cos4.field_log_derivative(Field::ON_AXIS, 0).unwrap(), 0.0);
        assert!(table.field_log_derivative(Field::ON_AXIS, 1).unwrap_err().contains("on axis"));
        let e = table.field_log_derivative(Field::new(10f64.to_radians(), 0.0), 0).unwrap_err();
        assert!(e.contains("kink") && e.contains("10°"), "{e}");
    }

    /// cos⁴θ: 1 on axis; at 20° along x, cos⁴(20°) = 0.779 751 …; along a diagonal the angle from
    /// the axis, `tan²θ = tan²θx + tan²θy`.
    #[test]
    fn cos4_is_the_fourth_power_of_the_angle_from_the_axis() {
        let ri = RelativeIllumination::Cos4;
        assert_eq!(ri.at(Field::ON_AXIS).unwrap(), 1.0);
        let x = 20f64.to_radians();
        assert!((ri.at(Field::new(x, 0.0)).unwrap() - x.cos().powi(4)).abs() < 1e-15);
        assert!((ri.at(Field::new(0.0, -x)).unwrap() - x.cos().powi(4)).abs() < 1e-15);
        let (a, b) = (10f64.to_radians(), 15f64.to_radians());
        let theta = (a.tan().powi(2) + b.tan().powi(2)).sqrt().atan();
        assert!((ri.at(Field::new(a, b)).unwrap() - theta.cos().powi(4)).abs() < 1e-15);
        assert_eq!(RelativeIllumination::None.at(Field::new(x, x)).unwrap(), 1.0);
    }

    /// A table interpolates linearly in the angle and is not extrapolated.
    #[test]
    fn a_table_interpolates_and_stops_at_its_ends() {
        let deg = |d: f64| d.to_radians();
        let ri = RelativeIllumination::table("ri.csv", vec![0.0, deg(10.0), deg(20.0)], vec![1.0, 0.9, 0.7]).unwrap();
        assert_eq!(ri.at(Field::ON_AXIS).unwrap(), 1.0);
        assert!((ri.at(Field::new(deg(15.0), 0.0)).unwrap() - 0.8).abs() < 1e-12);
        assert!((ri.at(Field::new(deg(20.0), 0.0)).unwrap() - 0.7).abs() < 1e-12);
        let e = ri.at(Field::new(deg(25.0), 0.0)).unwrap_err().to_string();
        assert!(e.contains("25") && e.contains("not extrapolated"), "{e}");
        assert!(ri.describe().contains("ri.csv (3 points, 0–20°)"), "{}", ri.describe());
        for bad in [-0.1, 1.5, f64::NAN] {
            assert!(RelativeIllumination::constant(bad).is_err(), "{bad}");
            assert!(RelativeIllumination::table("t", vec![0.0], vec![bad]).is_err(), "{bad}");
        }
        assert!(RelativeIllumination::table("t", vec![0.2, 0.1], vec![1.0, 1.0]).is_err());
        assert!(RelativeIllumination::table("t", vec![-0.1], vec![1.0]).is_err());
        assert!(RelativeIllumination::table("t", vec![], vec![]).is_err());
    }
}
