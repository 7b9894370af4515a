//! Built-in lens families for the ASNR toolkit, each a [`optics::LensModel`].
//!
//! - [`ChromaticMetalens`]: a chromatic metalens or diffractive lens, `f(λ) = f0 λ0/λ`
//!   (docs/physics.md "Lens families"), with first-order efficiency τ1(λ) and total transmission T(λ)
//!   constant or tabulated; through an iris ([`ChromaticMetalens::with_aperture`]) both scale by
//!   its area fraction (photon counts follow the pupil).
//! - [`Refractive`]: the ideal refractive reference, `W = 0`, or with glass dispersion
//!   `f(λ) = f0 (n0 − 1)/(n(λ) − 1)` ([`Sellmeier`]), `τ = T` from the Fresnel or coated
//!   surface losses.
//! - [`DispersionEngineered`]: an achromat over a design band whose aperture must fit the
//!   group-delay range of its meta-atom library (or, [`DelayOverflow::Reduced`], is partly chromatic).
//! - [`Harmonic`]: a multi-order diffractive lens of design order p, orders m with
//!   `τ_m = τ_base sinc²(pλ0/λ − m)` and `W020_m(λ) = (1 − mλ/(pλ0)) f0/(8F#²)`.
//! - [`Interleaved`]: a spatially multiplexed lens of N interleaved chromatic channels λ_j,
//!   `τ_j = η_j/N²`, `W020_j(λ) = (1 − λ/λ_j) f0/(8F#²)`.
//! - [`Segmented`]: a spatially multiplexed lens of N chromatic channels in zones of area
//!   fractions a_j ([`Layout`]: concentric rings, sectors, or a user's map), one composite pupil
//!   ([`optics::Pupil::Zones`]) with the zone wavefronts `W_j = (1 − λ/λ_j) f0/(8F#²) ρ²`,
//!   efficiency `Σ a_j η_j`; the other channels' light as signal or, [`OtherChannels`], as
//!   background outside each channel's band.
//! - [`Tabulated`]: one order whose OTF is a measured or simulated table
//!   ([`optics::Pupil::Table`]) with efficiency and transmission tables, a contained pixel MTF
//!   divided out; the tables come from text: [`parse_zemax_fft_mtf`] (Zemax FFT MTF listings in
//!   UTF-16, UTF-8 or Latin-1) with [`zemax_otf_table`], or [`mtf_table_from_rows`] (the rows of a long CSV, read by `scene`).
//! - [`PhaseLens`]: a designer's lens given by its phase profile at λ0 (Zemax Binary 2
//!   coefficients, [`binary2_profile`], or a radial table, plus a freeform spline of knots,
//!   [`spline_profile`]), with an explicit [`Dispersion`]
//!   (geometric phase, a diffractive kinoform of design order p, a fixed optical path), evaluated
//!   against the exact reference sphere ([`optics::Pupil::Radial`]; off axis the oblique wave's
//!   field aberrations).
//! - [`LibraryLens`]: a metalens of meta-atoms from a [`Library`] (complex transmission against
//!   parameters and wavelength) placed by a layout of rings, in the local periodic approximation:
//!   the first order's pupil from the zone-Fourier coefficient `c_1(ρ)`, τ1 and T from the field.
//! - [`LibraryMapLens`]: the same library's atoms on a 2-D square lattice ([`AtomGrid`], from a
//!   grid or a GDSII layout as drawn): each cell's field held over it, its mean against the
//!   reference sphere the design order, on the FFT path ([`optics::Pupil::Map`]).
//! - [`PsfStack`]: a lens given by its PSFs at a few wavelengths (a simulated or measured stack):
//!   each slice normalized, its centroid the order's image shift, its OTF about the centroid by
//!   FFT into an [`optics::OtfTable`] (tangential along x, sagittal along y) up to the stack's
//!   Nyquist frequency.
//! - [`presets`]: the paper's lens and published devices by name ([`preset`], [`preset_names`]).
//!
//! The wavefront sign is one (docs/physics.md, "Sign of the wavefront"): `W020 > 0` focuses
//! behind the detector. Efficiencies τ and the transmission T are fractions of the power incident
//! on the full clear aperture: a sub-aperture, zone, obscuration or sector carries its area
//! fraction in τ (docs/physics.md, "Lens families").
//!
//! Constructors validate every parameter (finite, in its physical range, `τ1 ≤ T ≤ 1`) and
//! return [`Error`] naming the parameter, its value and what is accepted, so a constructed lens
//! cannot produce NaN.
//!
//! # Example
//! ```
//! use lenses::{ChromaticMetalens, Curve};
//! use optics::LensModel;
//! // the paper's lens: F/2.5, f0 = 3.36 mm, λ0 = 800 nm, τ1 = 0.15, T = 0.55
//! let lens = ChromaticMetalens::new(2.5, 3.36e-3, 800e-9, Curve::Constant(0.15), Curve::Constant(0.55))
//!     .unwrap();
//! assert_eq!(lens.efficiency(850e-9), 0.15);
//! // 50 nm above the design wavelength the focus moves f0 Δλ/λ0 ≈ 0.2 mm toward the lens, in
//! // front of the detector: W020 = (1 − λ/λ0) f0/(8 F#²) = −0.0625 × 3.36e-3 / 50 = −4.2 µm
//! // (W020 > 0 is a focus behind the detector, docs/physics.md "Sign of the wavefront")
//! let w020 = lens.defocus(850e-9);
//! assert!((w020 + 4.2e-6).abs() < 1e-12);
//! ```
//!
//! Units: SI (m). Efficiencies are fractions of the light incident on the full aperture. This
//! crate reads no files: the parsers take text.

mod atom_grid;
mod chromatic;
mod dispersion;
mod exact;
mod harmonic;
mod interleaved;
mod library;
mod library_map;
mod phase;
mod phase_map;
pub mod presets;
mod psf;
mod refractive;
mod segmented;
mod tabulated;

pub use atom_grid::{AtomGrid, LayoutStats};
pub use chromatic::{ChromaticMetalens, Curve};
pub use dispersion::{DelayOverflow, DispersionEngineered, max_diameter, required_group_delay};
pub use exact::{ExactPupilMap, exact_map_refusal};
pub use harmonic::{HARMONIC_ORDER_REACH, Harmonic, sinc};
pub use interleaved::{Channel, Interleaved};
pub use library::{AtomErrors, FirstOrderDerivative, Interpolation, Library, LibraryLens};
pub use library_map::{Handedness, LibraryMapLens};
pub use phase::{
    Dispersion, PhaseLens, SPLINE_MAX_KNOTS, SPLINE_MIN_KNOTS, WithZernike, binary2_profile, hyperbolic_binary2,
    spline_profile,
};
pub use phase_map::PhaseMapLens;
pub use presets::{preset, preset_names};
pub use psf::{
    PSF_BORDER_SAMPLES, PSF_CENTRE_TOLERANCE, PSF_MAX_ELEMENTS, PSF_MIN_SIDE, PSF_NEGATIVE_FLOOR, PSF_NEGATIVE_MASS,
    PSF_PADDING, PSF_SYMMETRY_AZIMUTHS, PSF_SYMMETRY_STRIDE, PSF_SYMMETRY_TOLERANCE, PsfReport, PsfStack,
};
pub use refractive::{Glass, Refractive, Sellmeier, Surfaces, fresnel_reflectance};
pub use segmented::{Layout, OtherChannels, Segmented, ZoneMap};
pub use tabulated::{
    FieldChoice, PIXEL_DIVISION_LIMIT, Tabulated, ZemaxField, ZemaxMtf, decode_text, mtf_table_from_rows,
    parse_zemax_fft_mtf, zemax_otf_table,
};

/// What can be wrong with a lens description.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A parameter is outside its physical range.
    #[error("{name} = {value} is out of range: expected {expected}")]
    OutOfRange {
        /// Parameter name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What is accepted.
        expected: &'static str,
    },
    /// The imaging efficiency exceeds the total transmission somewhere.
    #[error(
        "efficiency τ1 = {efficiency} exceeds transmission T = {transmission} at {wavelength_nm} nm: expected τ1 ≤ T ≤ 1"
    )]
    EfficiencyAboveTransmission {
        /// Where, nm.
        wavelength_nm: f64,
        /// τ1 there.
        efficiency: f64,
        /// T there.
        transmission: f64,
    },
    /// A dispersion-engineered lens whose aperture needs more group delay than its library has.
    #[error(
        "the achromatic aperture needs a group-delay range ΔT_req = {required_fs:.2} fs but the meta-atom library provides ΔT_lib = {library_fs:.2} fs: at this focal length the library allows at most D = {max_diameter_um:.1} µm (F/{max_f_number:.2}); use a smaller aperture (a larger F-number), a library of larger range, or delay_overflow = reduced"
    )]
    GroupDelayExceeded {
        /// ΔT_req, fs.
        required_fs: f64,
        /// ΔT_lib, fs.
        library_fs: f64,
        /// The largest diameter the library allows at the focal length, µm.
        max_diameter_um: f64,
        /// The F-number at that diameter.
        max_f_number: f64,
    },
    /// Text (a Zemax listing, a CSV) that is not what was expected.
    #[error("{}expected {expected}, found `{found}`", line_prefix(*.line))]
    Parse {
        /// The line, from 1 (0: the text as a whole).
        line: usize,
        /// What was expected there.
        expected: String,
        /// What was found.
        found: String,
    },
    /// An OTF table that optics refuses (a row not 1 at zero frequency, values beyond [−1, 1], …).
    #[error("OTF table: {0}")]
    Table(optics::Error),
    /// A profile or pupil that optics refuses (a radial table not reaching the rim, a Noll
    /// index out of range, …).
    #[error("{0}")]
    Pupil(optics::Error),
    /// A preset name that does not exist.
    #[error("unknown lens preset `{name}`: expected one of {known}")]
    UnknownPreset {
        /// The name given.
        name: String,
        /// The names known, comma-separated.
        known: String,
    },
    /// A 2-D meta-atom layout the library lens cannot take (the numbers in the message).
    #[error("{0}")]
    Layout(String),
    /// A lens the flat lens's exact pupil map cannot take (`options.pupil_mapping = "exact"`):
    /// the message says why and what it takes.
    #[error("{0}")]
    Mapping(String),
    /// A PSF stack that cannot be used (a NaN or negative sample, a slice without light, a
    /// shape that does not fit): the message names the slice, its wavelength and the sample.
    #[error("PSF stack: {0}")]
    PsfStack(String),
    /// A table said to contain the pixel MTF exceeds 1 once divided by it.
    #[error(
        "the table divided by the pixel MTF of {pitch_um} µm is {value} > 1 at {wavelength_nm} nm, {frequency_cyc_per_mm} cycles/mm: the table does not contain that pixel MTF (check the pitch, or give none)"
    )]
    PixelMtfNotInTable {
        /// Where, nm.
        wavelength_nm: f64,
        /// Where, cycles/mm.
        frequency_cyc_per_mm: f64,
        /// The divided value.
        value: f64,
        /// The pixel pitch, µm.
        pitch_um: f64,
    },
}

fn line_prefix(line: usize) -> String {
    if line == 0 { String::new() } else { format!("line {line}: ") }
}
