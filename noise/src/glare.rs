//! Veiling glare from spurious diffraction orders and the glare-inclusive SNR (paper SI eq.
//! S10–S14). Plain ratios of levels or photoelectron counts; no validation (NaN in, NaN out).

/// Veiling glare `VG = black/white` (paper SI eq. S10); both levels relative to the capped black.
pub fn veiling_glare(black: f64, white: f64) -> f64 {
    black / white
}

/// Modulation `M = (white − black)/(white + black)` (paper SI eq. S11).
pub fn modulation(white: f64, black: f64) -> f64 {
    (white - black) / (white + black)
}

/// `M = (1 − VG)/(1 + VG)` (paper SI eq. S12).
pub fn modulation_from_glare(vg: f64) -> f64 {
    (1.0 - vg) / (1.0 + vg)
}

/// Inverse of eq. S12: `VG = (1 − M)/(1 + M)`.
pub fn glare_from_modulation(m: f64) -> f64 {
    (1.0 - m) / (1.0 + m)
}

/// Zero-frequency modulation of a diffractive lens, `M0 = τ1/T` (paper SI eq. S13, Buralli and
/// Morris), with τ1 the first-order efficiency and T the total transmission, both relative to
/// the light incident on the aperture and averaged over aperture and spectrum.
pub fn buralli_morris_modulation(efficiency: f64, transmission: f64) -> f64 {
    efficiency / transmission
}

/// SNR including veiling glare, `S/√S_N` (paper SI eq. S14): `signal` photoelectrons from the
/// imaging order (eq. S8 with τ1) over the shot noise of `total` photoelectrons from all
/// transmitted light (eq. S8 with τ1 → T).
pub fn snr_with_glare(signal: f64, total: f64) -> f64 {
    signal / total.sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_glare_numbers() {
        // τ1 = 0.15, T = 0.55: M0 = 0.15/0.55 = 0.272727…; VG = 0.727273/1.272727 = 0.571429
        let m0 = buralli_morris_modulation(0.15, 0.55);
        assert!((m0 - 3.0 / 11.0).abs() < 1e-15);
        assert!((glare_from_modulation(m0) - 4.0 / 7.0).abs() < 1e-15);
    }

    #[test]
    fn s10_s11_s12_are_consistent() {
        // white 200, black 60: VG = 0.3; M = 140/260 = 0.538462 = (1 − 0.3)/(1 + 0.3)
        let vg = veiling_glare(60.0, 200.0);
        assert!((vg - 0.3).abs() < 1e-15);
        assert!((modulation(200.0, 60.0) - modulation_from_glare(vg)).abs() < 1e-15);
        assert!((glare_from_modulation(modulation_from_glare(vg)) - vg).abs() < 1e-15);
    }

    #[test]
    fn s14_hand_worked() {
        // S = 1000 e⁻ from τ1, S_N = 3667 e⁻ from T (= 1000 × 0.55/0.15): SNR = 1000/√3667 = 16.514
        let snr = snr_with_glare(1000.0, 1000.0 * 0.55 / 0.15);
        assert!((snr - 16.514).abs() < 1e-3, "{snr}");
    }
}
