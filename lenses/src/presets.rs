//! Named lenses of the paper and of published devices, built by [`preset`] (the names:
//! [`preset_names`]) or by their functions here.
//!
//! Each preset states its publication and the numbers taken from it. Where a preset needs a
//! number the publication (as cited here) does not give, the doc says so and the value chosen is
//! stated and conservative: efficiencies low rather than high, a meta-atom library no larger
//! than the published aperture needs. The efficiency has no published law in NA or band
//! (docs/physics.md, "Lens families"): it is an input, never extrapolated to another aperture.

use optics::LensModel;

use crate::{
    ChromaticMetalens, Curve, DelayOverflow, DispersionEngineered, Error, Glass, Refractive, Sellmeier, Surfaces,
};

/// The names [`preset`] knows.
pub const PRESET_NAMES: &[&str] =
    &["paper-chromatic", "chen2019", "wang2018", "ndao2020", "ndao2020-reduced", "n-bk7-singlet"];

/// The names [`preset`] knows, for error messages and listings.
pub fn preset_names() -> &'static [&'static str] {
    PRESET_NAMES
}

/// The lens of preset `name` ([`preset_names`]). `ndao2020` is the device as published and is
/// refused ([`Error::GroupDelayExceeded`], see [`ndao2020`]); `ndao2020-reduced` accepts it with
/// its achromatism reduced.
pub fn preset(name: &str) -> Result<Box<dyn LensModel + Send + Sync>, Error> {
    Ok(match name {
        "paper-chromatic" => Box::new(paper_chromatic()),
        "chen2019" => Box::new(chen2019()?),
        "wang2018" => Box::new(wang2018()?),
        "ndao2020" => Box::new(ndao2020(DelayOverflow::Reject)?),
        "ndao2020-reduced" => Box::new(ndao2020(DelayOverflow::Reduced)?),
        "n-bk7-singlet" => Box::new(n_bk7_singlet()),
        _ => return Err(Error::UnknownPreset { name: name.to_owned(), known: PRESET_NAMES.join(", ") }),
    })
}

/// The paper's chromatic metalens (J. Engelberg et al., *How good is your metalens?
/// Experimental verification of metalens performance criterion*): F/2.5, f0 = 3.36 mm
/// (D = 1.344 mm), λ0 = 800 nm, first-order efficiency τ1 = 0.15 and total transmission
/// T = 0.55, constant.
pub fn paper_chromatic() -> ChromaticMetalens {
    ChromaticMetalens::new(2.5, 3.36e-3, 800e-9, Curve::Constant(0.15), Curve::Constant(0.55))
        .expect("the paper's parameters are in range")
}

/// The focal length (m) of a lens of diameter `diameter_m` and numerical aperture `na`:
/// `NA = R/√(R² + F²)` ⇒ `F = R √(1/NA² − 1)`.
fn focal_length_from_na(diameter_m: f64, na: f64) -> f64 {
    0.5 * diameter_m * (1.0 / (na * na) - 1.0).sqrt()
}

/// W. T. Chen et al., *A broadband achromatic polarization-insensitive metalens consisting of
/// anisotropic nanostructures*, Nat. Commun. 10, 355 (2019): TiO₂, achromatic over 460–700 nm,
/// NA 0.2, D = 26.4 µm, so F = 64.7 µm (F/2.45); the aperture needs ΔT_req = 4.45 fs.
///
/// Not given by the numbers cited here, chosen: the meta-atom library's range ΔT_lib = 4.5 fs
/// (the published aperture's requirement rounded up: the device was built, so its library
/// covered at least that, and no more is assumed); the band-average efficiency τ = 0.20
/// (conservative, half the ≈ 40 % of [`wang2018`]); the transmission T = 0.90 (a dielectric
/// metasurface on glass, about the substrate's two Fresnel losses).
pub fn chen2019() -> Result<DispersionEngineered, Error> {
    let d = 26.4e-6;
    let f = focal_length_from_na(d, 0.2);
    DispersionEngineered::new(
        f / d,
        f,
        (460e-9, 700e-9),
        4.5e-15,
        Curve::Constant(0.20),
        Curve::Constant(0.90),
        DelayOverflow::Reject,
    )
}

/// S. Wang et al., *A broadband achromatic metalens in the visible*, Nat. Nanotechnol. 13, 227
/// (2018): GaN, achromatic over 400–660 nm, NA 0.106, D = 50 µm, f = 235 µm (F/4.7), about 40 %
/// band-average efficiency (τ = 0.40); the aperture needs ΔT_req = 4.42 fs.
///
/// Not given by the numbers cited here, chosen: ΔT_lib = 4.5 fs (the requirement rounded up, as
/// [`chen2019`]); T = 0.90 (as [`chen2019`]).
pub fn wang2018() -> Result<DispersionEngineered, Error> {
    let (d, f) = (50e-6, 235e-6);
    DispersionEngineered::new(
        f / d,
        f,
        (400e-9, 660e-9),
        4.5e-15,
        Curve::Constant(0.40),
        Curve::Constant(0.90),
        DelayOverflow::Reject,
    )
}

/// S. Ndao et al., *Octave bandwidth photonic fishnet-achromatic-metalens*, Nat. Commun. 11,
/// 3205 (2020): achromatic over 640–1200 nm, NA 0.12, D = 10 µm, so F = 41.4 µm (F/4.14), a
/// meta-atom library of ΔT_lib = 0.97 fs, about 70 % of the transmitted light focused. The
/// aperture needs ΔT_req = 1.00 fs > 0.97 fs: as published ([`DelayOverflow::Reject`]) the
/// design is refused with both delays; [`DelayOverflow::Reduced`] keeps β = 0.97 of the
/// achromatism.
///
/// Not given by the numbers cited here, chosen: T = 0.80 (conservative for a fishnet of
/// stacked layers), so τ = 0.7 T = 0.56.
pub fn ndao2020(overflow: DelayOverflow) -> Result<DispersionEngineered, Error> {
    let d = 10e-6;
    let f = focal_length_from_na(d, 0.12);
    DispersionEngineered::new(
        f / d,
        f,
        (640e-9, 1200e-9),
        0.97e-15,
        Curve::Constant(0.7 * 0.80),
        Curve::Constant(0.80),
        overflow,
    )
}

/// An uncoated N-BK7 singlet in the paper's geometry (F/2.5, f0 = 3.36 mm at λ0 = 800 nm, the
/// paper lens's design wavelength): Schott's Sellmeier coefficients ([`Sellmeier::N_BK7`]), two
/// bare surfaces, `τ = T = (1 − R)²` with the Fresnel reflectance at each wavelength
/// (0.917 at n = 1.5168), thin-lens dispersion (docs/physics.md, "Lens families").
pub fn n_bk7_singlet() -> Refractive {
    Refractive::new(2.5, 3.36e-3, 800e-9, Glass::Sellmeier(Sellmeier::N_BK7), 1, Surfaces::Uncoated)
        .expect("the singlet's parameters are in range")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::required_group_delay;

    #[test]
    fn every_name_builds_except_the_published_ndao_lens() {
        for name in preset_names() {
            let built = preset(name);
            if *name == "ndao2020" {
                let Err(e) = built else { panic!("ndao2020 as published must be refused") };
                let text = e.to_string();
                assert!(text.contains("ΔT_req = 1.00 fs") && text.contains("ΔT_lib = 0.97 fs"), "{text}");
            } else {
                let lens = built.unwrap_or_else(|e| panic!("{name}: {e}"));
                assert!(lens.f_number() > 0.5, "{name}");
            }
        }
        let Err(e) = preset("chen") else { panic!("an unknown name") };
        assert!(e.to_string().contains("unknown lens preset `chen`: expected one of paper-chromatic, chen2019"), "{e}");
    }

    /// The published geometries: F from NA and D, and the group delays of docs/physics.md
    /// ("Lens families": Chen 4.45 fs, Ndao 1.00 fs).
    #[test]
    fn geometries_and_group_delays_follow_the_publications() {
        let chen = chen2019().unwrap();
        assert!((chen.focal_length() - 64.67e-6).abs() < 0.01e-6, "{}", chen.focal_length());
        let d = chen.focal_length() / chen.f_number();
        assert!((d - 26.4e-6).abs() < 1e-15);
        let req = required_group_delay(chen.focal_length(), d);
        assert!((req - 4.45e-15).abs() < 0.005e-15, "{req}");
        let wang = wang2018().unwrap();
        assert!((wang.numerical_aperture() - 0.106).abs() < 0.001 * 5.0, "{}", wang.numerical_aperture());
        assert!((required_group_delay(235e-6, 50e-6) - 4.42e-15).abs() < 0.01e-15);
        assert_eq!(wang.efficiency(500e-9), 0.40);
        let ndao = ndao2020(DelayOverflow::Reduced).unwrap();
        let d = ndao.focal_length() / ndao.f_number();
        assert!((required_group_delay(ndao.focal_length(), d) - 1.00e-15).abs() < 0.005e-15);
        assert!((ndao.efficiency(900e-9) - 0.7 * ndao.transmission(900e-9)).abs() < 1e-15);
        let p = paper_chromatic();
        assert_eq!((p.f_number(), p.efficiency(800e-9), p.transmission(800e-9)), (2.5, 0.15, 0.55));
        let bk7 = n_bk7_singlet();
        assert!((bk7.transmission(587.56e-9) - 0.91745).abs() < 1e-4, "{}", bk7.transmission(587.56e-9));
    }
}
