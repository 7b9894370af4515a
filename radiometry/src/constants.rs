//! Physical constants (SI, CODATA 2018 exact values where defined).

/// Planck constant h, J s (exact since the 2019 SI redefinition).
pub const PLANCK: f64 = 6.626_070_15e-34;

/// Speed of light in vacuum c, m/s (exact).
pub const SPEED_OF_LIGHT: f64 = 299_792_458.0;

/// Boltzmann constant k, J/K (exact).
pub const BOLTZMANN: f64 = 1.380_649e-23;

/// Stefan–Boltzmann constant σ = 2π⁵k⁴/(15h³c²), W/(m² K⁴), derived from the exact constants
/// above (CODATA 2018 lists 5.670 374 419... × 10⁻⁸).
pub const STEFAN_BOLTZMANN: f64 = 2.0 * PI5 * (BOLTZMANN * BOLTZMANN * BOLTZMANN * BOLTZMANN)
    / (15.0 * (PLANCK * PLANCK * PLANCK) * (SPEED_OF_LIGHT * SPEED_OF_LIGHT));

/// Second radiation constant c₂ = hc/k, m K (Planck's law exponent is c₂/(λT)).
pub const SECOND_RADIATION_CONSTANT: f64 = PLANCK * SPEED_OF_LIGHT / BOLTZMANN;

const PI5: f64 = core::f64::consts::PI
    * core::f64::consts::PI
    * core::f64::consts::PI
    * core::f64::consts::PI
    * core::f64::consts::PI;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stefan_boltzmann_matches_codata() {
        // CODATA 2018: sigma = 5.670374419e-8 W m^-2 K^-4 (10 significant digits, truncated).
        assert!((STEFAN_BOLTZMANN / 5.670_374_419e-8 - 1.0).abs() < 1e-9);
    }

    #[test]
    fn second_radiation_constant_matches_codata() {
        // CODATA 2018: c2 = 1.438776877e-2 m K.
        assert!((SECOND_RADIATION_CONSTANT / 1.438_776_877e-2 - 1.0).abs() < 1e-9);
    }
}
