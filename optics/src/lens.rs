//! The `LensModel` trait and its vocabulary: what a lens does to light of one wavelength from
//! one field point.
//!
//! A lens model *describes*; the optics crate *computes*. A model answers which imaging orders
//! reach the detector, with what efficiency, through which pupil and with what wavefront error at
//! the detector plane, and how much light it transmits in total. The polychromatic engine
//! ([`crate::Polychromatic`]) turns that into transfer functions, choosing the fast exact 1-D
//! path where the description allows it.

use std::fmt;
use std::sync::Arc;

/// A field point: the chief-ray angle of the object point, radians.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[non_exhaustive]
pub struct Field {
    /// Field angle along x, radians.
    pub x_rad: f64,
    /// Field angle along y, radians.
    pub y_rad: f64,
}

impl Field {
    /// The optical axis.
    pub const ON_AXIS: Field = Field { x_rad: 0.0, y_rad: 0.0 };

    /// A field point at angles `(x, y)`, radians.
    pub fn new(x_rad: f64, y_rad: f64) -> Field {
        Field { x_rad, y_rad }
    }

    /// Whether this is the optical axis.
    pub fn is_on_axis(&self) -> bool {
        self.x_rad == 0.0 && self.y_rad == 0.0
    }
}

/// The pupil an imaging order passes through.
///
/// Photon counts follow the pupil's area (docs/physics.md, "Lens families"): an order's
/// [`efficiency`](Order::efficiency) is a fraction of the light incident on the **full** clear
/// aperture, so an order through a pupil of area fraction `a` ([`Pupil::area_fraction`]) carries
/// at most `a` of it; a lens model puts the area in the efficiency (a sector of 10° collects
/// 1/36 of the light of the full lens), and `optics::testkit` checks `efficiency ≤ a`.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub enum Pupil {
    /// The lens' full circular aperture of diameter `D = f0/F#`, centred on the axis.
    Full,
    /// Any other aperture, in units of the full aperture's radius (decentred iris, annulus,
    /// sector or segment, mask): computed on the FFT path.
    Aperture(Arc<crate::fft::Aperture>),
    /// Several zones of one aperture, coherent at one wavelength (a segmented multiplexed lens):
    /// one composite pupil whose field is `amplitude_j exp(i 2π W_j/λ)` in zone `j`, computed on
    /// the FFT path. Each zone's [`Zone::wavefront`] replaces the order's wavefront there (it is
    /// written in full-aperture coordinates, so an off-centre zone's defocus is also a tilt); the
    /// order's `image_shift_m` applies to all zones, and its `defocus_m` should be the zone
    /// defocus of largest size (it sizes the frequency rule and the Fraunhofer check, which take
    /// the largest zone defocus when that is larger; the spectral panels follow every zone's
    /// defocus). The order's efficiency is `Σ amplitude_j² × area fraction_j` times nothing else:
    /// the zones' amplitudes carry their efficiencies. The grid is normalized by that power, so
    /// the order's OTF is 1 at zero frequency (`fft::SampledZones`, `fft::OtfPlan::otf_of_field`).
    /// Keep the zones' `Arc<Aperture>`s the same from call to call: their sampling is cached.
    Zones(Arc<[Zone]>),
    /// No pupil: the order's OTF is given as a table against wavelength and frequency (a
    /// measured or simulated MTF, e.g. a Zemax FFT MTF export), read at ν directly below the
    /// order's cutoff `1/(λ F#)`; its tangential curve along the field direction (`+x` on
    /// axis). The order's wavefront is not used except `image_shift_m`; the order's `defocus_m`
    /// may be set for the Fraunhofer check. On the exact 1-D path with other full-pupil orders,
    /// or beside the FFT layer's grids; the spectral panels are cut at the table's wavelengths.
    Table(Arc<crate::OtfTable>),
    /// The full circular aperture with a radially symmetric field given as data
    /// ([`crate::radial::RadialPupil`]: an amplitude profile, wavefront terms beyond the order's
    /// defocus, Zernike terms): a designer's phase profile or meta-atom library. The order's
    /// `defocus_m` is the profile's best-fit defocus plus any other (build it with
    /// [`Order::radial`]); its other Seidel terms add as on [`Full`](Pupil::Full). Symmetric
    /// (every Zernike term `m = 0`, no other Seidel term) it is computed by the radial engine
    /// (the autocorrelation integral, `radial` module); otherwise on the FFT path.
    Radial(Arc<crate::radial::RadialPupil>),
    /// A 2-D map of cells ([`crate::map::MapPupil`]: a designer's phase map, each sample held
    /// over its cell, in a circular or square aperture), computed on the FFT path. The order's
    /// `defocus_m` is the map's best-fit defocus (build it with [`Order::map`]); its other
    /// wavefront terms are not used. The square collects `4/π` of the circle's light
    /// ([`area_fraction`](Pupil::area_fraction)).
    Map(Arc<crate::map::MapPupil>),
}

impl Pupil {
    /// The fraction of the full aperture's area `π R²` this pupil transmits: 1 for
    /// [`Full`](Pupil::Full) and [`Table`](Pupil::Table) (a measured OTF carries its area in its
    /// efficiency), the aperture's area over π, and for [`Zones`](Pupil::Zones) the
    /// power-weighted sum `Σ amplitude_j² area_j/π`. A mask's area is measured on a 512² grid
    /// with supersampled edge pixels.
    pub fn area_fraction(&self) -> f64 {
        match self {
            Pupil::Full | Pupil::Table(_) | Pupil::Radial(_) => 1.0,
            Pupil::Aperture(a) => a.area_fraction(),
            Pupil::Zones(zones) => zones.iter().map(|z| z.amplitude * z.amplitude * z.aperture.area_fraction()).sum(),
            Pupil::Map(m) => m.aperture().area_fraction(),
        }
    }
}

/// One zone of a composite pupil ([`Pupil::Zones`]).
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct Zone {
    /// The zone's region, in units of the full aperture's radius, centred on the lens axis.
    pub aperture: Arc<crate::fft::Aperture>,
    /// Field amplitude transmission, ≥ 0: the zone passes `amplitude²` of the power incident on it.
    pub amplitude: f64,
    /// The zone's wavefront (defocus and Seidel terms, full-aperture coordinates, the sign of
    /// [`Wavefront`]). Its `image_shift_m` Δ is applied as a tilt of this zone alone,
    /// `W += (Δx x + Δy y) NA` (x, y in units of the full aperture's radius, `NA = 1/(2F#)`),
    /// which moves the zone's image by Δ, the way the order's shift (which applies to all zones
    /// on top) moves the order's: zones of a multiplexed lens off axis each have their own
    /// lateral colour.
    pub wavefront: Wavefront,
}

impl Zone {
    /// A zone `aperture` with field `amplitude` and `wavefront`.
    pub fn new(aperture: Arc<crate::fft::Aperture>, amplitude: f64, wavefront: Wavefront) -> Zone {
        Zone { aperture, amplitude, wavefront }
    }
}

/// Wavefront error of an imaging order at the exit pupil, relative to a reference sphere
/// centred on the detector point, in metres of optical path at the pupil edge.
///
/// Sign (docs/physics.md, "Sign of the wavefront"), the one every lens and every engine follows: `W` is
/// the optical path of the actual wavefront relative to the reference sphere centred on the
/// detector point; the pupil field is `A exp(+i 2π W/λ)` with time dependence `exp(−iωt)`.
/// `W020 > 0` means the wave focuses **behind** the detector (farther from the lens): a focus
/// `Δz` behind it gives `W020 = Δz NA²/2`. The Seidel terms carry the same sign (`W040 > 0`: the
/// marginal zone focuses behind the paraxial focus; `W220 > 0`: the field point focuses behind
/// the detector), and `W220` adds to `W020`. For pure defocus the OTF is even in `W020`; any other
/// term, a decentred pupil with lateral colour, or a sum over orders, reveals the sign.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[non_exhaustive]
pub struct Wavefront {
    /// Defocus coefficient `W020` (m): `W(ρ) = W020 ρ²` with ρ the normalized pupil radius.
    ///
    /// Paraxially a focus shift `Δz` behind the detector gives `W020 = Δz NA²/2 = Δz/(8 F#²)`;
    /// a focus in front of the detector gives `W020 < 0`.
    pub defocus_m: f64,
    /// Lateral displacement `(x, y)` of the image point on the detector from the field's reference
    /// image point, m: a wavefront tilt. It leaves the MTF of one wavelength unchanged but gives
    /// each wavelength of a polychromatic sum its own phase `exp(−2πi ν·Δ)` (lateral colour).
    pub image_shift_m: [f64; 2],
    /// Seidel coefficients at this field point (the field along +x), m at the pupil edge, with
    /// the sign of [`defocus_m`](Self::defocus_m): spherical `W040 ρ⁴`, coma `W131 ρ³ cos φ`,
    /// astigmatism `W222 ρ² cos² φ`, field curvature `W220 ρ²` (the `H = 1` values of
    /// [`crate::fft::Aberrations`]). Any non-zero term sends the order to the FFT path.
    pub spherical_m: f64,
    /// Coma `W131` (m), see [`spherical_m`](Self::spherical_m).
    pub coma_m: f64,
    /// Astigmatism `W222` (m).
    pub astigmatism_m: f64,
    /// Field curvature `W220` (m).
    pub field_curvature_m: f64,
}

impl Wavefront {
    /// A wavefront with defocus only.
    pub fn defocus(w020_m: f64) -> Wavefront {
        Wavefront { defocus_m: w020_m, ..Wavefront::default() }
    }

    /// Whether the wavefront is defocus (and tilt) only, as the exact 1-D path requires.
    pub fn is_defocus_only(&self) -> bool {
        self.spherical_m == 0.0 && self.coma_m == 0.0 && self.astigmatism_m == 0.0 && self.field_curvature_m == 0.0
    }

    /// The FFT path's aberration set for this wavefront (tilt excluded: it is applied as a phase).
    pub fn aberrations(&self) -> crate::fft::Aberrations {
        crate::fft::Aberrations {
            w020_m: self.defocus_m,
            w040_m: self.spherical_m,
            w131_m: self.coma_m,
            w222_m: self.astigmatism_m,
            w220_m: self.field_curvature_m,
            field: 1.0,
            ..crate::fft::Aberrations::default()
        }
    }

    /// This wavefront with the image point displaced by `(x, y)` m on the detector.
    pub fn shifted(self, x_m: f64, y_m: f64) -> Wavefront {
        Wavefront { image_shift_m: [x_m, y_m], ..self }
    }
}

/// One imaging order (a diffraction order, or one channel of a multiplexed lens).
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct Order {
    /// Fraction of the light incident on the aperture that this order brings to the image
    /// (for a metalens, the first-order efficiency τ1 of paper SI eq. S7), in `[0, 1]`.
    pub efficiency: f64,
    /// The pupil this order is imaged through.
    pub pupil: Pupil,
    /// Its wavefront error at the detector.
    pub wavefront: Wavefront,
}

impl Order {
    /// An order through `pupil` with `efficiency` and `wavefront`.
    pub fn new(efficiency: f64, pupil: Pupil, wavefront: Wavefront) -> Order {
        Order { efficiency, pupil, wavefront }
    }

    /// An order through the radially symmetric pupil `pupil` ([`Pupil::Radial`]) whose defocus
    /// is `wavefront.defocus_m` plus the pupil's best-fit defocus
    /// ([`RadialPupil::fitted_defocus_m`](crate::radial::RadialPupil::fitted_defocus_m)), which
    /// the pupil leaves out of its own terms: the order's `W020` is then the defocus that sizes
    /// the spectral panels and the Fraunhofer check.
    pub fn radial(efficiency: f64, pupil: Arc<crate::radial::RadialPupil>, wavefront: Wavefront) -> Order {
        let wavefront = Wavefront { defocus_m: wavefront.defocus_m + pupil.fitted_defocus_m(), ..wavefront };
        Order { efficiency, pupil: Pupil::Radial(pupil), wavefront }
    }

    /// An order through the 2-D map `pupil` ([`Pupil::Map`]) whose `defocus_m` is the map's
    /// best-fit defocus ([`MapPupil::fitted_defocus_m`](crate::map::MapPupil::fitted_defocus_m)):
    /// it sizes the spectral panels and the Fraunhofer check.
    pub fn map(efficiency: f64, pupil: Arc<crate::map::MapPupil>) -> Order {
        let wavefront = Wavefront { defocus_m: pupil.fitted_defocus_m(), ..Wavefront::default() };
        Order { efficiency, pupil: Pupil::Map(pupil), wavefront }
    }
}

/// The lens of [`LensModel::affine_defocus`]: one full-pupil order, `W020(λ) = w0 + w1 λ`,
/// constant efficiency and transmission.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AffineDefocus {
    /// Imaging efficiency τ1 (fraction), the same at every wavelength.
    pub efficiency: f64,
    /// Total transmission T (fraction), the same at every wavelength.
    pub transmission: f64,
    /// `w0`: W020 extrapolated to λ = 0, m.
    pub w020_intercept_m: f64,
    /// `w1 = dW020/dλ` (dimensionless).
    pub w020_slope: f64,
}

/// A lens's efficiency tables factored out of its orders ([`LensModel::factored_efficiency`]):
/// the lens's orders at λ are the orders of every part's `relative` lens together, each
/// order's efficiency `t_p(λ)` times that of the same order of its part's `relative`.
///
/// The spectral rules integrate the detected spectrum against the interpolation basis by its
/// exact moments, whatever its number of table rows (docs/physics.md, "Spectral quadrature"); a
/// table in the lens's efficiency instead kinks the lens's part of the integrand at every row,
/// and each row cuts a spectral panel. Multiplied into the detected spectrum, a table costs no
/// more than a spectrum table: `ρ(λ) τ_o(λ) = [ρ(λ) t_p(λ)] r_o(λ)` with `r_o` the efficiency
/// of order `o` of part `p`'s `relative`, smooth in λ. A lens whose orders carry different
/// tables (the channels of a multiplexed lens) has one part per table; the polychromatic OTF is
/// linear in the orders, so each part is integrated with the moments of its own `ρ t_p`
/// ([`crate::Polychromatic::with_parts`]).
#[derive(Clone, Debug)]
pub struct FactoredEfficiency {
    /// The parts, at least one.
    pub parts: Vec<FactoredPart>,
    /// The lens's total transmission `T(λ)` as a spectrum factor (the glare estimate integrates
    /// the detected spectrum times it exactly, paper SI eq. S13): a transmission table then cuts
    /// no spectral panel either.
    pub transmission: radiometry::Spectrum,
}

/// What [`LensModel::aperture_directions`] gives: per order `[P, T, S]`, or why they cannot be
/// given.
pub type ApertureDirections = Result<Vec<[crate::radial::RadialProfile; 3]>, String>;

/// What [`LensModel::defocus_rates`] gives: per m of wavelength, `∂W020/∂λ` (m per m) of the
/// one order's defocus, `∂ln τ/∂λ` of its efficiency and `∂ln T/∂λ` of the transmission.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DefocusRates {
    /// `∂W020/∂λ`.
    pub defocus: f64,
    /// `∂ln τ/∂λ`, per m.
    pub ln_efficiency: f64,
    /// `∂ln T/∂λ`, per m.
    pub ln_transmission: f64,
}

/// What [`LensModel::order_wavelength_rates`] gives: per m of wavelength, for each order of
/// [`LensModel::orders`] in its order `[∂W020_o/∂λ, ∂τ_o/∂λ]` (m per m, per m), and `∂ln T/∂λ`
/// of the transmission.
#[derive(Clone, Debug, PartialEq)]
pub struct OrderWavelengthRates {
    /// `[∂W020_o/∂λ, ∂τ_o/∂λ]` per order.
    pub orders: Vec<[f64; 2]>,
    /// `∂ln T/∂λ`, per m.
    pub ln_transmission: f64,
}

/// What [`LensModel::wavelength_directions`] gives: the coefficients `c_k` and per order the
/// profiles `p_k` (m, as functions of `q = ρ²`) of the wavefront's rate `δW = Σ_k c_k p_k`, or why
/// they cannot be given.
pub type WavelengthDirections = Result<(Vec<f64>, Vec<Vec<crate::radial::RadialProfile>>), String>;

/// How a lens's imaging orders and transmission move with one of its design parameters at one
/// wavelength ([`LensModel::order_derivatives`]): per unit of the parameter.
#[derive(Clone, Debug)]
pub struct OrderDerivatives {
    /// `∂τ_o`, one per order of [`LensModel::orders`].
    pub efficiencies: Vec<f64>,
    /// `∂T` ([`LensModel::transmission`]).
    pub transmission: f64,
    /// Per order (a radial pupil's), the change of its field amplitude `∂A` and of its whole
    /// wavefront `∂W` (m), as functions of `q = ρ²`.
    pub fields: Vec<(crate::radial::RadialProfile, crate::radial::RadialProfile)>,
    /// Per order (a site map's, [`MapPupil::sites`](crate::map::MapPupil::sites)), the change
    /// of its atoms' table `∂t_u` ([`MapPupil::field_derivative`](crate::map::MapPupil::field_derivative));
    /// empty where the orders are radial pupils.
    pub tables: Vec<Arc<[num_complex::Complex64]>>,
}

/// A scene key that moves the zones of a composite pupil ([`Pupil::Zones`]) each at its own
/// rate ([`LensModel::zone_rates`]; docs/physics.md, "Gradients: the multiplexed lens").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ZoneKey {
    /// The field angle along x (`0`) or y (`1`), per radian: each zone's own image shift (its
    /// lateral colour) moves at its own rate.
    FieldAngle(usize),
    /// Channel `j`'s design wavelength λ_j, per relative change (`∂/∂ln λ_j`): zone `j`'s
    /// defocus and image shift.
    ChannelWavelength(usize),
    /// Channel `j`'s own efficiency η_j, per relative change (`∂/∂ln η_j`): zone `j`'s field
    /// amplitude `√η_j` and the order's efficiency.
    ChannelEfficiency(usize),
    /// Zone `j`'s area fraction a_j, per relative change (`∂/∂ln a_j`): the zones' edges that
    /// move with it (rings' radii, wedges' angles: [`ZoneRate::edges`]) and the order's
    /// efficiency `Σ a_k η_k`.
    AreaFraction(usize),
}

/// How one zone of a composite pupil moves with a [`ZoneKey`], per unit of the key.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ZoneRate {
    /// `∂a_j`, the zone's field amplitude.
    pub amplitude: f64,
    /// `∂W020_j`, m: the zone's defocus about the lens axis.
    pub defocus_m: f64,
    /// `∂Δ_j`, m: the zone's own image shift (its tilt `Δ_j NA`).
    pub image_shift_m: [f64; 2],
    /// The motion of the zone's edges: `∂` of its aperture's inner radius, outer radius (units
    /// of the full aperture's radius), and its wedge's start and end angles (radians), as
    /// [`Aperture::edge_rates_in`](crate::fft::Aperture::edge_rates_in) orders them.
    pub edges: [f64; 4],
}

/// How one order moves with a [`ZoneKey`] ([`LensModel::zone_rates`]): each of its zones (none
/// where the order is not a composite pupil of zones) and its efficiency `∂τ_o`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ZoneRates {
    /// One per zone of the order's [`Pupil::Zones`], in order.
    pub zones: Vec<ZoneRate>,
    /// `∂τ_o`.
    pub efficiency: f64,
}

/// One part of a [`FactoredEfficiency`]: a table and the orders it multiplies.
#[derive(Clone, Debug)]
pub struct FactoredPart {
    /// `t_p(λ)`, a factor of the efficiency of each of this part's orders (a table, or a
    /// product of a constant and a table; `Constant(1)` where only the transmission was a
    /// table).
    pub table: radiometry::Spectrum,
    /// The part's orders with `t_p` divided out: the same pupils and wavefronts, each order's
    /// efficiency `τ_o(λ)/t_p(λ)`, defined where `t_p(λ) = 0` too, with no row of any table
    /// among its [`breakpoints`](LensModel::breakpoints). Its transmission is not read.
    pub relative: Arc<dyn LensModel>,
}

/// The `parameter` of [`LensModel::order_derivatives`] that stands for the σ (radians) of a
/// library lens's per-atom phase errors `e^{iσδ_i}`, each atom's draw `δ_i` held (a fixed seed):
/// docs/physics.md, "Gradients: a library's atoms' phase errors".
pub const ATOM_PHASE_ERROR: usize = usize::MAX;

/// The `parameter` of [`LensModel::order_derivatives`] that stands for the σ of a 2-D library
/// layout's per-atom relative amplitude errors, taken in expectation over the draws:
/// docs/physics.md, "Gradients: a library's atoms' phase errors".
pub const ATOM_TRANSMISSION_ERROR: usize = usize::MAX - 1;

/// What a lens does to light: the trait every lens family implements.
///
/// Object safe (`&dyn LensModel`, `Box<dyn LensModel>` work), `Send + Sync + Debug`, plain `f64` in SI
/// units. Three methods are required; the rest have defaults built on them.
///
/// Architecture invariant: the detector sits at [`focal_length`](LensModel::focal_length) `f0`
/// behind the lens, and [`f_number`](LensModel::f_number) is `f0/D`; everything
/// wavelength-dependent (focus shift, efficiency) is expressed through [`orders`](LensModel::orders).
///
/// Wavefront sign: every implementation reports its orders' [`Wavefront`] in the convention of
/// docs/physics.md, "Sign of the wavefront" (see [`Wavefront`]): `W020 > 0` is a focus behind the
/// detector. A chromatic lens `f(λ) = f0 λ0/λ` thus has `W020(λ) = (1 − λ/λ0) f0/(8 F#²)`,
/// negative for `λ > λ0`.
///
/// Photon counts follow the pupil: an order's efficiency is a fraction of the light incident on
/// the full aperture, at most its [`Pupil::area_fraction`]. `optics::testkit::check_lens`
/// (feature `testkit`) checks an implementation against these rules and the transfer-function
/// invariants; `examples/custom-lens` in the repository is a whole downstream crate.
///
/// # Implementing it
/// A chromatic metalens behind an iris that opens a 90° sector of its aperture: one order
/// through a [`Pupil::Aperture`], with the sector's area fraction (1/4) in its efficiency and
/// its transmission. Nothing is hidden: this is the whole implementation.
///
/// ```
/// use std::sync::Arc;
/// use optics::fft::Aperture;
/// use optics::{Field, LensModel, Order, Pupil, Wavefront};
///
/// #[derive(Debug)]
/// struct QuarterMetalens {
///     aperture: Arc<Aperture>,
/// }
///
/// impl LensModel for QuarterMetalens {
///     fn f_number(&self) -> f64 {
///         2.5
///     }
///
///     fn focal_length(&self) -> f64 {
///         3.36e-3
///     }
///
///     fn orders(&self, wavelength_m: f64, _field: Field) -> Vec<Order> {
///         // f(λ) = f0 λ0/λ with the detector at f0: W020 = (1 − λ/λ0) f0/(8F#²)
///         let w020 = (1.0 - wavelength_m / 800e-9) * 3.36e-3 / (8.0 * 2.5 * 2.5);
///         let efficiency = 0.15 * self.aperture.area_fraction();
///         vec![Order::new(efficiency, Pupil::Aperture(self.aperture.clone()), Wavefront::defocus(w020))]
///     }
///
///     fn transmission(&self, _wavelength_m: f64) -> f64 {
///         0.55 * self.aperture.area_fraction()
///     }
/// }
///
/// let lens = QuarterMetalens { aperture: Arc::new(Aperture::sector(0.0, std::f64::consts::FRAC_PI_2).unwrap()) };
/// assert!((lens.efficiency(800e-9) - 0.15 / 4.0).abs() < 1e-15);
/// ```
pub trait LensModel: Send + Sync + fmt::Debug {
    /// Working F-number `F# = f0/D` at the detector.
    fn f_number(&self) -> f64;

    /// Distance from the lens to the detector (the design focal length `f0`), m.
    fn focal_length(&self) -> f64;

    /// The imaging orders for light of `wavelength_m` from `field`.
    fn orders(&self, wavelength_m: f64, field: Field) -> Vec<Order>;

    /// [`orders`](LensModel::orders) appended to `out`: the same orders, for a caller that reads
    /// many wavelengths through one buffer (a product rule asks at every point of every level).
    /// The default appends what `orders` returns; a lens may push its orders directly and save
    /// the allocation of a vector a call.
    fn orders_into(&self, wavelength_m: f64, field: Field, out: &mut Vec<Order>) {
        out.extend(self.orders(wavelength_m, field));
    }

    /// Imaging efficiency at `wavelength_m` on axis: the sum of the orders' efficiencies.
    fn efficiency(&self, wavelength_m: f64) -> f64 {
        self.orders(wavelength_m, Field::ON_AXIS).iter().map(|o| o.efficiency).sum()
    }

    /// Total transmission `T(λ)` into all orders, focused or not (paper SI eq. S13).
    /// The default is [`efficiency`](LensModel::efficiency): a lens without stray orders.
    fn transmission(&self, wavelength_m: f64) -> f64 {
        self.efficiency(wavelength_m)
    }

    /// Wavelengths (m) where the efficiency or transmission has a kink (samples of a table);
    /// spectral quadratures split their panels there. Default: none.
    fn breakpoints(&self) -> Vec<f64> {
        Vec::new()
    }

    /// The lens's efficiency and transmission tables factored out of its orders
    /// ([`FactoredEfficiency`]), where it has some: `metric::evaluate` then folds each part's
    /// table into the detected spectrum, so that their rows cost what a spectrum table's do.
    /// Default: `None`.
    fn factored_efficiency(&self) -> Option<FactoredEfficiency> {
        None
    }

    /// The change of each imaging order's whole wavefront (m, as a function of `q = ρ²`) per unit
    /// of each Binary 2 coefficient `A_j` of the lens's phase, at `wavelength_m` on axis: one list
    /// per order of [`orders`](Self::orders), one profile per coefficient (docs/physics.md,
    /// "Gradients"). `None` (the default) where the lens has no such coefficients.
    fn binary2_directions(&self, _wavelength_m: f64) -> Option<Vec<Vec<crate::radial::RadialProfile>>> {
        None
    }

    /// How each imaging order's whole wavefront (m, as a function of `q = ρ²`) moves with the
    /// aperture, at `wavelength_m` on axis: one `[P, T, S]` per order of
    /// [`orders`](Self::orders), where the aperture radius `R = f0/(2F#)` moving with the focal
    /// length `f0` held changes the wavefront along `P + T` per unit `ln R` (`P` the profile's
    /// part, `T` the reference sphere's `R²q/√(R²q + f0²)`), and `f0` moving with `R` held along
    /// `S − T` (`S` the sphere `√(R²q + f0²) − f0` itself, homogeneous of degree 1 in `R` and
    /// `f0`). So `∂W/∂ln F#` (f0 held) is `−(P + T)` and `∂W/∂ln f0` (F# held) is `P + S`
    /// (docs/physics.md, "Gradients": the F-number and focal length of a phase lens). `None`
    /// (the default) where the lens does not give them; `Some(Err(why))` where it would but
    /// cannot here (something of it moves with the aperture that the directions do not follow).
    fn aperture_directions(&self, _wavelength_m: f64) -> Option<ApertureDirections> {
        None
    }

    /// How each imaging order's whole wavefront moves with the wavelength, at `wavelength_m` on
    /// axis, for the gradient with respect to a line's wavelength (docs/physics.md, "Gradients:
    /// a line's wavelength"): the radial engine turns a wavefront `W` (m) into the phase
    /// `2πW/λ` and reads the OTF at `s = νλF#`, so at a fixed frequency the OTF moves with λ by
    /// its `s` (the frequency scaling, taken by parts outside) and by the wavefront direction
    /// `δW = ∂W/∂λ − W/λ` (m per m) at the phase's fixed `2π/λ`. Given as
    /// `(coefficients c_k, per order the profiles p_k)`, `δW = Σ_k c_k p_k` with the same `c_k`
    /// for every order. `None` (the default) where the lens does not give them; `Some(Err(why))`
    /// where it would but cannot here (the orders' relative efficiencies or the efficiency's
    /// table move with λ, which the directions do not follow).
    fn wavelength_directions(&self, _wavelength_m: f64) -> Option<WavelengthDirections> {
        None
    }

    /// For a lens whose one order at `field` is a circle (the full pupil or a circular iris,
    /// decentred or not) with a defocus alone: how it moves with the wavelength at `wavelength_m`
    /// ([`DefocusRates`]), for the gradient
    /// with respect to a line's wavelength. `None` (the default) where the lens does not give
    /// them (then a defocus affine in λ with constant efficiencies,
    /// [`affine_defocus`](Self::affine_defocus), is used where the lens promises one).
    fn defocus_rates(&self, _wavelength_m: f64, _field: Field) -> Option<DefocusRates> {
        None
    }

    /// For a lens whose every order at `field` is the full circular pupil with a defocus alone:
    /// how each order at `wavelength_m` moves with the design wavelength λ0 (`lens.design_wavelength_nm`),
    /// `[∂W020_o/∂ln λ0, ∂τ_o/∂ln λ0]` per order of [`orders`](Self::orders), in its order (m,
    /// and per unit ln λ0), the total transmission `T` held; for the gradient with respect to
    /// λ0 (docs/physics.md, "Gradients: the design wavelength"). Off axis, where the orders are
    /// displaced, only where each order's image shift is `Δ_o = f0 tan θ (λ0 a_o(λ) − 1)` (the
    /// lateral colour of the chromatic and harmonic lenses): it moves as
    /// `∂Δ_o/∂ln λ0 = Δ_o + f0 tan θ`, its own scale and a translation common to every order and
    /// wavelength that turns the OTF by one phase and leaves the MTF as it is, so the image
    /// shifts' scale's lane gives its share (docs/physics.md, "Gradients: the design wavelength
    /// off axis"). `None` (the default) where the lens does not give them.
    fn design_wavelength_rates(&self, _wavelength_m: f64, _field: Field) -> Option<Vec<[f64; 2]>> {
        None
    }

    /// Whether nothing the lens images with depends on its design wavelength λ0 (its orders, at
    /// every wavelength and field point, and its transmission): a phase lens whose profile is
    /// given in radians and turns into a path `λ/2π` per radian at each wavelength (a geometric
    /// phase), where λ0 only names the wavelength the profile was designed at. The value's
    /// derivative with respect to λ0 is then 0 (docs/physics.md, "Gradients: the design
    /// wavelength"). `false` (the default) otherwise.
    fn design_wavelength_inert(&self) -> bool {
        false
    }

    /// For a lens whose every order at `field` is the full circular pupil with a defocus alone,
    /// several of them with efficiencies that move against each other with λ (the harmonic
    /// lens): how each moves with the wavelength at `wavelength_m` ([`OrderWavelengthRates`]),
    /// for the gradient with respect to a line's wavelength. `None` (the default) where the lens
    /// does not give them.
    fn order_wavelength_rates(&self, _wavelength_m: f64, _field: Field) -> Option<OrderWavelengthRates> {
        None
    }

    /// How each imaging order's image shift moves with the field angles, at `wavelength_m` and
    /// `field`: one `[∂Δx/∂θx, ∂Δy/∂θy]` (m per radian) per order of [`orders`](Self::orders),
    /// for a lens whose orders change with the field point only through their image shifts
    /// `Δx(λ, θx)`, `Δy(λ, θy)` (lateral colour; every other term of the order the same at every
    /// field point). `None` (the default) where the orders change otherwise with the field (an
    /// oblique wave's aberrations) or the lens does not give them (docs/physics.md, "Gradients:
    /// the field point").
    fn image_shift_field_rates(&self, _wavelength_m: f64, _field: Field) -> Option<Vec<[f64; 2]>> {
        None
    }

    /// Whether the orders are the same at every field point in the field's own frame (`+x` the
    /// field direction `atan2(θy, θx)`, their pupils, tables and image shifts turning with it
    /// and changing with nothing else: a PSF stack, the PSFs of one field point): the OTF along
    /// the detector's azimuth `φ` is then the frame's along `φ − atan2(θy, θx)`, so the mean MTF
    /// (over azimuth, or the tangential and sagittal means' average) does not depend on the field
    /// angles (docs/physics.md, "Gradients: the field point"). `false` (the default) otherwise.
    fn turns_with_field(&self) -> bool {
        false
    }

    /// How the lens's orders move with its design parameter `parameter` at `wavelength_m` on
    /// axis ([`OrderDerivatives`]; a library lens's parameter bias, one per library parameter:
    /// docs/physics.md, "Gradients: a library's parameter bias"; [`ATOM_PHASE_ERROR`]: the σ of
    /// its atoms' phase errors, every draw held). `None` (the default) where the lens has no such
    /// parameter or its value is not differentiable in it there.
    fn order_derivatives(&self, _wavelength_m: f64, _parameter: usize) -> Option<OrderDerivatives> {
        None
    }

    /// For a lens whose imaging orders are composite pupils of zones (a segmented multiplexed
    /// lens): how each order's zones and efficiency move with `key` at `wavelength_m` and
    /// `field`, one [`ZoneRates`] per order of [`orders`](Self::orders), every other term of
    /// the orders held (docs/physics.md, "Gradients: the multiplexed lens"). `None` (the
    /// default) where the lens does not give them or the value is not differentiable in `key`.
    fn zone_rates(&self, _wavelength_m: f64, _field: Field, _key: ZoneKey) -> Option<Vec<ZoneRates>> {
        None
    }

    /// The wavelength the lens was designed for (m), if it has one: the reference of the
    /// Fraunhofer-validity check (paper SI eq. S15). Default: none.
    fn design_wavelength(&self) -> Option<f64> {
        None
    }

    /// The band `(λ_min, λ_max)` (m) outside which the lens images nothing (every order's
    /// efficiency 0, the transmitted light background only) and inside which its orders are the
    /// design's: a dispersion-engineered lens's design band. The value's derivative with respect
    /// to an edge is a limit of the signal's integrals (docs/physics.md, "Gradients: the
    /// dispersion-engineered lens"). `None` (the default) for a lens without one.
    fn design_band(&self) -> Option<(f64, f64)> {
        None
    }

    /// Numerical aperture on the image side, paraxial: `NA0 = D/(2 f0) = 1/(2 F#)`.
    fn numerical_aperture(&self) -> f64 {
        0.5 / self.f_number()
    }

    /// A promise that enables the closed-form spectral integration ([`crate::GaussianDefocus`]):
    /// at `field`, for every wavelength, [`orders`](LensModel::orders) is one order through the
    /// full circular pupil whose only aberration is a defocus affine in λ,
    /// `W020(λ) = w0 + w1 λ`, with no image shift, and the efficiency and transmission do not
    /// depend on λ. Default: `None` (no promise). The promise is checked against `orders` at a
    /// few wavelengths before it is used.
    fn affine_defocus(&self, field: Field) -> Option<AffineDefocus> {
        let _ = field;
        None
    }

    /// Short human-readable description, for reports.
    fn describe(&self) -> String {
        format!(
            "lens F/{} f0 = {} mm",
            round_for_display(self.f_number()),
            round_for_display(self.focal_length() * 1e3)
        )
    }
}

/// `x` rounded to 12 significant digits, so that unit conversions print as typed
/// (`3.36e-3 m × 1e3` prints `3.36`, not `3.3600000000000003`).
pub fn round_for_display(x: f64) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    let digits = 11 - x.abs().log10().floor() as i32;
    let scale = 10f64.powi(digits);
    (x * scale).round() / scale
}

macro_rules! forward_lens_model {
    ($($ty:ty),*) => {$(
        impl<T: LensModel + ?Sized> LensModel for $ty {
            fn f_number(&self) -> f64 { (**self).f_number() }
            fn focal_length(&self) -> f64 { (**self).focal_length() }
            fn orders(&self, wavelength_m: f64, field: Field) -> Vec<Order> {
                (**self).orders(wavelength_m, field)
            }
            fn orders_into(&self, wavelength_m: f64, field: Field, out: &mut Vec<Order>) {
                (**self).orders_into(wavelength_m, field, out)
            }
            fn efficiency(&self, wavelength_m: f64) -> f64 { (**self).efficiency(wavelength_m) }
            fn transmission(&self, wavelength_m: f64) -> f64 { (**self).transmission(wavelength_m) }
            fn breakpoints(&self) -> Vec<f64> { (**self).breakpoints() }
            fn factored_efficiency(&self) -> Option<FactoredEfficiency> { (**self).factored_efficiency() }
            fn numerical_aperture(&self) -> f64 { (**self).numerical_aperture() }
            fn design_wavelength(&self) -> Option<f64> { (**self).design_wavelength() }
            fn design_band(&self) -> Option<(f64, f64)> { (**self).design_band() }
            fn binary2_directions(&self, wavelength_m: f64) -> Option<Vec<Vec<crate::radial::RadialProfile>>> {
                (**self).binary2_directions(wavelength_m)
            }
            fn aperture_directions(&self, wavelength_m: f64) -> Option<ApertureDirections> {
                (**self).aperture_directions(wavelength_m)
            }
            fn wavelength_directions(&self, wavelength_m: f64) -> Option<WavelengthDirections> {
                (**self).wavelength_directions(wavelength_m)
            }
            fn defocus_rates(&self, wavelength_m: f64, field: Field) -> Option<DefocusRates> {
                (**self).defocus_rates(wavelength_m, field)
            }
            fn image_shift_field_rates(&self, wavelength_m: f64, field: Field) -> Option<Vec<[f64; 2]>> {
                (**self).image_shift_field_rates(wavelength_m, field)
            }
            fn turns_with_field(&self) -> bool { (**self).turns_with_field() }
            fn order_wavelength_rates(&self, wavelength_m: f64, field: Field) -> Option<OrderWavelengthRates> {
                (**self).order_wavelength_rates(wavelength_m, field)
            }
            fn design_wavelength_rates(&self, wavelength_m: f64, field: Field) -> Option<Vec<[f64; 2]>> {
                (**self).design_wavelength_rates(wavelength_m, field)
            }
            fn design_wavelength_inert(&self) -> bool {
                (**self).design_wavelength_inert()
            }
            fn order_derivatives(&self, wavelength_m: f64, parameter: usize) -> Option<OrderDerivatives> {
                (**self).order_derivatives(wavelength_m, parameter)
            }
            fn zone_rates(&self, wavelength_m: f64, field: Field, key: ZoneKey) -> Option<Vec<ZoneRates>> {
                (**self).zone_rates(wavelength_m, field, key)
            }
            fn describe(&self) -> String { (**self).describe() }
            fn affine_defocus(&self, field: Field) -> Option<AffineDefocus> { (**self).affine_defocus(field) }
        }
    )*};
}
forward_lens_model!(&T, Box<T>, Arc<T>);

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug)]
    struct Perfect;
    impl LensModel for Perfect {
        fn f_number(&self) -> f64 {
            2.0
        }
        fn focal_length(&self) -> f64 {
            0.01
        }
        fn orders(&self, _: f64, _: Field) -> Vec<Order> {
            vec![Order::new(0.9, Pupil::Full, Wavefront::default())]
        }
    }

    fn takes_dyn(lens: &dyn LensModel) -> f64 {
        lens.transmission(5e-7) + lens.numerical_aperture()
    }

    #[test]
    fn object_safe_with_forwarding_impls() {
        let boxed: Box<dyn LensModel> = Box::new(Perfect);
        let arc: Arc<dyn LensModel> = Arc::new(Perfect);
        let expected = 0.9 + 0.25;
        assert_eq!(takes_dyn(&Perfect), expected);
        assert_eq!(takes_dyn(&boxed), expected);
        assert_eq!(takes_dyn(&arc), expected);
        assert_eq!(takes_dyn(&&Perfect), expected);
    }
}
