//! The segmented spatially multiplexed lens: N chromatic channels side by side in one aperture.

use std::f64::consts::TAU;
use std::fmt;
use std::sync::Arc;

use optics::fft::Aperture;
use optics::{Field, LensModel, Order, Pupil, Wavefront, Zone, ZoneKey, ZoneRate, ZoneRates};

use crate::Error;
use crate::chromatic::{Curve, check, check_efficiency_below_transmission, check_fraction};
use crate::interleaved::Channel;

/// A user's zone map: `(x, y)` in the pupil's normalized coordinates (`[-1, 1]²`, units of the
/// full aperture's radius, origin on the lens axis) to the index of the channel whose zone
/// holds the point, or `None` where the aperture is opaque. Points outside the unit circle are
/// opaque whatever the map says.
pub type ZoneMap = dyn Fn(f64, f64) -> Option<usize> + Send + Sync;

/// How the channels' zones tile the aperture of a [`Segmented`] lens.
#[derive(Clone)]
pub enum Layout {
    /// Concentric zones, the first channel innermost: channel `j` fills the ring
    /// `r_{j−1} ≤ r ≤ r_j`, `r_j = √(a_1 + … + a_j)` (radius in units of the full aperture's), so
    /// that its area fraction is `a_j`; with `Σ a_j < 1` the rim beyond `r_N` is opaque.
    Concentric,
    /// Sectors (wedges from the centre to the rim): channel `j` spans the angles
    /// `[2π (a_1 + … + a_{j−1}), 2π (a_1 + … + a_j)]`, the first starting at `+x` and going
    /// counter-clockwise; with `Σ a_j < 1` the last wedge up to `+x` is opaque.
    Sectors,
    /// Any zones: a [`ZoneMap`]. The area fractions are measured from the map
    /// ([`Aperture::area_fraction`] of each zone, on a 512² grid with supersampled edge pixels).
    Mask(Arc<ZoneMap>),
}

impl fmt::Debug for Layout {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Layout::Concentric => "Concentric",
            Layout::Sectors => "Sectors",
            Layout::Mask(_) => "Mask(<zone map>)",
        })
    }
}

/// Where a [`Segmented`] lens counts the light a channel brings to the detector at wavelengths
/// other than its own.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum OtherChannels {
    /// Every zone's light at every wavelength is signal, each with its own defocus in the one
    /// composite pupil: at λ the other channels form a defocused image on top of the focused
    /// one, as the paper treats its chromatic lens (docs/physics.md, "Lens families").
    #[default]
    Signal,
    /// A zone's light is signal only in its channel's band, where that channel is the one in
    /// focus; elsewhere it reaches the detector as background (noise only, within `T`). The
    /// bands tile the spectrum at the midpoints between neighbouring channel wavelengths (in
    /// wavelength order): channel `j`'s band is `[(λ_{j−1} + λ_j)/2, (λ_j + λ_{j+1})/2)`, the
    /// outermost bands reaching half the adjacent spacing beyond λ_1 and λ_N (one channel: every
    /// wavelength). So at each wavelength at most one zone, that of the nearest channel, is
    /// imaged: the defocus of the channel in focus is at most
    /// `(Δλ/2)/λ_j · f0/(8F#²)` for channel spacing Δλ, and a colour sensor that assigns the
    /// bands to its colour channels sees no crosstalk counted as signal. Outside all bands
    /// nothing is signal (τ = 0).
    Background,
}

/// A segmented spatially multiplexed achromat: N chromatic channels, channel `j` designed to
/// focus λ_j at `f0` and occupying a zone of area fraction `a_j` of the aperture
/// (docs/physics.md, "Lens families").
///
/// - Efficiency: zone `j` passes η_j(λ) of the light incident on it, so it brings
///   `τ_j(λ) = a_j η_j(λ)` of the light incident on the full aperture to the detector
///   (photon counts follow the pupil area); the lens' imaging efficiency is `Σ_j a_j η_j(λ)`
///   ([`OtherChannels::Signal`]), at most the total transmission `T(λ)`.
/// - Wavefront: the zones of one aperture are coherent at one wavelength, so the lens forms one
///   image through one composite pupil ([`Pupil::Zones`]) with a piecewise wavefront: in zone
///   `j` the field is `√η_j(λ) exp(i 2π W_j/λ)` with
///   `W_j(x, y) = (1 − λ/λ_j) · f0/(8F#²) · (x² + y²)/R²` in full-aperture coordinates
///   (docs/physics.md, "Sign of the wavefront": `W020 > 0` focuses behind the detector). An
///   off-centre zone sees that defocus about the lens axis, i.e. defocus about its own centre
///   plus a tilt: its defocused image is displaced.
/// - Off axis, channel `j`'s image sits at `f_j(λ) tan θ` behind a remote stop, so zone `j`
///   carries the lateral colour `f0 tan θ (λ_j/λ − 1)` as its own image shift.
///
/// Multiplexing keeps the in-focus spectral density of a chromatic lens (each wavelength is
/// focused only by the zone of its channel), so it does not raise the broadband ASNR: its gain
/// is colour fidelity and the choice of each channel's band.
#[derive(Clone, Debug)]
pub struct Segmented {
    f_number: f64,
    focal_length: f64,
    channels: Vec<Channel>,
    layout: Layout,
    /// the zones' apertures, built once and shared by every `orders` call
    zones: Vec<Arc<Aperture>>,
    /// the zones' area fractions as built (exact for rings and sectors, measured for masks): the
    /// `a_j` of the efficiencies, so that `τ ≤` the pupil's area
    areas: Vec<f64>,
    transmission: Curve,
    other_channels: OtherChannels,
    /// each channel's band for [`OtherChannels::Background`], `[lo, hi)`, m
    bands: Vec<(f64, f64)>,
}

/// How close to 1 the area fractions' sum counts as the zones filling the aperture
/// ([`LensModel::zone_rates`] of [`ZoneKey::AreaFraction`]: the construction's own `1e-12`).
const FILLED: f64 = 1e-12;

/// Side of the grid on which a [`Layout::Mask`] is scanned for zone indices beyond the channels.
const MASK_INDEX_SCAN: usize = 256;

impl Segmented {
    /// A segmented lens of working F-number `f_number` (≥ 0.5) and focal length
    /// `focal_length_m` (> 0) with 1 to 16 `channels` (design wavelengths finite, > 0 and
    /// distinct, in the layout's order; efficiencies fractions), zones laid out by `layout` with
    /// area fractions `area_fractions` (`None`: `1/N` each; each finite and > 0, `Σ a_j ≤ 1`;
    /// must be `None` for [`Layout::Mask`], whose areas are measured) and total transmission
    /// `transmission` (a fraction, `Σ a_j η_j ≤ T` at every wavelength).
    pub fn new(
        f_number: f64,
        focal_length_m: f64,
        channels: Vec<Channel>,
        layout: Layout,
        area_fractions: Option<Vec<f64>>,
        transmission: Curve,
    ) -> Result<Self, Error> {
        check("f_number", f_number, f_number >= 0.5, "a finite number ≥ 0.5 (NA = 1/(2F#) ≤ 1)")?;
        check("focal_length", focal_length_m, focal_length_m > 0.0, "a finite length > 0 m")?;
        let n = channels.len();
        check("channels", n as f64, (1..=16).contains(&n), "1 to 16 channels")?;
        for (j, c) in channels.iter().enumerate() {
            let l = c.wavelength_m;
            check("channels.wavelength", l, l > 0.0, "a finite wavelength > 0 m")?;
            check(
                "channels.wavelength",
                l,
                channels[..j].iter().all(|o| o.wavelength_m != l),
                "distinct channel wavelengths (one channel per wavelength)",
            )?;
            check_fraction("channels.efficiency", &c.efficiency)?;
        }
        check_fraction("transmission", &transmission)?;
        let (zones, areas) = match &layout {
            Layout::Mask(map) => {
                if let Some(a) = &area_fractions {
                    return Err(Error::OutOfRange {
                        name: "area_fractions",
                        value: a.len() as f64,
                        expected: "none with a mask layout (its zones' areas are measured from the map)",
                    });
                }
                mask_zones(map, n)?
            }
            layout => {
                let areas = match area_fractions {
                    None => vec![1.0 / n as f64; n],
                    Some(a) => a,
                };
                check("area_fractions", areas.len() as f64, areas.len() == n, "one area fraction per channel")?;
                for &a in &areas {
                    check("area_fractions", a, a > 0.0, "a finite fraction > 0 of the aperture's area")?;
                }
                let total: f64 = areas.iter().sum();
                check("area_fractions (sum)", total, total <= 1.0 + 1e-12, "Σ a_j ≤ 1: the zones fit in the aperture")?;
                let zones = match layout {
                    Layout::Concentric => rings(&areas),
                    _ => sectors(&areas),
                };
                let measured = zones.iter().map(|z| z.area_fraction()).collect();
                (zones, measured)
            }
        };
        let bands = bands(&channels);
        let lens = Segmented {
            f_number,
            focal_length: focal_length_m,
            channels,
            layout,
            zones,
            areas,
            transmission,
            other_channels: OtherChannels::Signal,
            bands,
        };
        let parts: Vec<&Curve> = lens.channels.iter().map(|c| &c.efficiency).collect();
        check_efficiency_below_transmission(
            &|l| lens.signal_efficiency(l, OtherChannels::Signal),
            &parts,
            &lens.transmission,
            lens.centre(),
        )?;
        Ok(lens)
    }

    /// This lens with the other channels' light counted as `other_channels` (default
    /// [`OtherChannels::Signal`]).
    pub fn with_other_channels(self, other_channels: OtherChannels) -> Self {
        Segmented { other_channels, ..self }
    }

    /// The family's name.
    pub fn kind(&self) -> &'static str {
        "multiplexed-segmented"
    }

    /// The channels, in the layout's order.
    pub fn channels(&self) -> &[Channel] {
        &self.channels
    }

    /// The layout.
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// Where the other channels' light counts.
    pub fn other_channels(&self) -> OtherChannels {
        self.other_channels
    }

    /// The zones' area fractions `a_j` as built: the given fractions (to rounding) for rings and
    /// sectors, measured for masks.
    pub fn area_fractions(&self) -> &[f64] {
        &self.areas
    }

    /// Channel `j`'s band `[lo, hi)` (m) where [`OtherChannels::Background`] counts its light as
    /// signal.
    pub fn band(&self, j: usize) -> (f64, f64) {
        self.bands[j]
    }

    /// The focused efficiency of zone `j` at `wavelength_m`: `a_j η_j(λ)`, or 0 outside the
    /// channel's band with [`OtherChannels::Background`].
    pub fn zone_efficiency(&self, j: usize, wavelength_m: f64) -> f64 {
        self.areas[j] * self.signal_eta(j, wavelength_m, self.other_channels)
    }

    /// Defocus of zone `j` at `wavelength_m`: `W020_j = (1 − λ/λ_j) f0/(8F#²)`.
    pub fn zone_defocus(&self, j: usize, wavelength_m: f64) -> f64 {
        (1.0 - wavelength_m / self.channels[j].wavelength_m) * self.focal_length / (8.0 * self.f_number * self.f_number)
    }

    /// η_j(λ) where zone `j`'s light is signal, else 0.
    fn signal_eta(&self, j: usize, wavelength_m: f64, other: OtherChannels) -> f64 {
        let (lo, hi) = self.bands[j];
        let lit = other == OtherChannels::Signal || (wavelength_m >= lo && wavelength_m < hi);
        if lit { self.channels[j].efficiency.value(wavelength_m) } else { 0.0 }
    }

    fn signal_efficiency(&self, wavelength_m: f64, other: OtherChannels) -> f64 {
        (0..self.channels.len()).map(|j| self.areas[j] * self.signal_eta(j, wavelength_m, other)).sum()
    }

    fn centre(&self) -> f64 {
        let (lo, hi) = self
            .channels
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), c| (lo.min(c.wavelength_m), hi.max(c.wavelength_m)));
        0.5 * (lo + hi)
    }
}

/// Concentric rings of areas `a_j`, the first innermost ([`Aperture::ring`], exact edge areas).
fn rings(areas: &[f64]) -> Vec<Arc<Aperture>> {
    let mut cumulative: f64 = 0.0;
    areas
        .iter()
        .map(|a| {
            let inner = cumulative.sqrt();
            cumulative += a;
            let outer = cumulative.sqrt().min(1.0);
            Arc::new(Aperture::ring(inner, outer, None).expect("0 ≤ inner < outer ≤ 1: areas > 0, Σ ≤ 1"))
        })
        .collect()
}

/// Sectors of angular widths `2π a_j` from `+x`, counter-clockwise.
fn sectors(areas: &[f64]) -> Vec<Arc<Aperture>> {
    let mut start = 0.0;
    areas
        .iter()
        .map(|a| {
            let end = start + TAU * a.min(1.0);
            let aperture = Aperture::sector(start, end).expect("a sector of width in (0, 2π]");
            start = end;
            Arc::new(aperture)
        })
        .collect()
}

/// The zones of a mask layout and their measured areas; refuses an index beyond the channels
/// and a channel without area.
fn mask_zones(map: &Arc<ZoneMap>, n: usize) -> Result<(Vec<Arc<Aperture>>, Vec<f64>), Error> {
    let h = 2.0 / MASK_INDEX_SCAN as f64;
    for i in 0..MASK_INDEX_SCAN {
        for k in 0..MASK_INDEX_SCAN {
            let (x, y) = (-1.0 + (i as f64 + 0.5) * h, -1.0 + (k as f64 + 0.5) * h);
            if let Some(j) = map(x, y).filter(|&j| j >= n && x * x + y * y <= 1.0) {
                return Err(Error::OutOfRange {
                    name: "mask zone index",
                    value: j as f64,
                    expected: "a channel index below the number of channels (or None: opaque)",
                });
            }
        }
    }
    let mut zones = Vec::with_capacity(n);
    let mut areas = Vec::with_capacity(n);
    for j in 0..n {
        let map = Arc::clone(map);
        let zone = Aperture::mask(move |x, y| x * x + y * y <= 1.0 && map(x, y) == Some(j));
        let area = zone.area_fraction();
        check("mask zone area", area, area > 0.0, "every channel's zone has an area > 0 in the mask")?;
        zones.push(Arc::new(zone));
        areas.push(area);
    }
    Ok((zones, areas))
}

/// Each channel's band (module docs of [`OtherChannels::Background`]), in the channels' order.
fn bands(channels: &[Channel]) -> Vec<(f64, f64)> {
    let mut sorted: Vec<f64> = channels.iter().map(|c| c.wavelength_m).collect();
    sorted.sort_by(f64::total_cmp);
    let n = sorted.len();
    channels
        .iter()
        .map(|c| {
            if n == 1 {
                return (0.0, f64::INFINITY);
            }
            let i = sorted.iter().position(|&l| l == c.wavelength_m).expect("a channel's own wavelength");
            let lo = if i == 0 { sorted[0] - 0.5 * (sorted[1] - sorted[0]) } else { 0.5 * (sorted[i - 1] + sorted[i]) };
            let hi = if i == n - 1 {
                sorted[n - 1] + 0.5 * (sorted[n - 1] - sorted[n - 2])
            } else {
                0.5 * (sorted[i] + sorted[i + 1])
            };
            (lo.max(0.0), hi)
        })
        .collect()
}

impl LensModel for Segmented {
    fn f_number(&self) -> f64 {
        self.f_number
    }

    fn focal_length(&self) -> f64 {
        self.focal_length
    }

    /// One order through the composite pupil of the zones (type docs); its `defocus_m` is the
    /// zone defocus of largest size among the zones that carry light (all zones when none does).
    fn orders(&self, wavelength_m: f64, field: Field) -> Vec<Order> {
        let (tx, ty) = (field.x_rad.tan(), field.y_rad.tan());
        let mut efficiency = 0.0;
        let (mut largest_lit, mut largest): (f64, f64) = (0.0, 0.0);
        let zones: Vec<Zone> = (0..self.channels.len())
            .map(|j| {
                let eta = self.signal_eta(j, wavelength_m, self.other_channels);
                efficiency += self.areas[j] * eta;
                let amplitude = eta.sqrt();
                let w020 = self.zone_defocus(j, wavelength_m);
                if w020.abs() > largest.abs() {
                    largest = w020;
                }
                if amplitude > 0.0 && w020.abs() > largest_lit.abs() {
                    largest_lit = w020;
                }
                let k = self.channels[j].wavelength_m / wavelength_m - 1.0;
                let shift = [self.focal_length * tx * k, self.focal_length * ty * k];
                Zone::new(Arc::clone(&self.zones[j]), amplitude, Wavefront::defocus(w020).shifted(shift[0], shift[1]))
            })
            .collect();
        let any_lit = zones.iter().any(|z| z.amplitude > 0.0);
        let defocus = if any_lit { largest_lit } else { largest };
        vec![Order::new(efficiency, Pupil::Zones(zones.into()), Wavefront::defocus(defocus))]
    }

    fn efficiency(&self, wavelength_m: f64) -> f64 {
        self.signal_efficiency(wavelength_m, self.other_channels)
    }

    /// The zones' rates of the one order (docs/physics.md, "Gradients: the multiplexed lens"):
    /// a field angle θ_a moves every zone's lateral colour `Δ_j = f0 tan θ_a (λ_j/λ − 1)` by
    /// `f0 sec²θ_a (λ_j/λ − 1)`; `ln λ_j` moves zone `j`'s defocus by `(λ/λ_j) f0/(8F#²)` and its
    /// lateral colour by `f0 tan θ λ_j/λ`; `ln η_j` moves zone `j`'s amplitude `√η_j` by `√η_j/2`
    /// and the order's efficiency `Σ a_k η_k` by `a_j η_j` where the zone's light is signal.
    /// `None` for a channel beyond the lens's, for λ_j with [`OtherChannels::Background`] (the
    /// channels' band edges move with it: the zones' light switches between signal and
    /// background there, kinks of the integrand over λ), and for η_j where the zone is lit with
    /// `η_j = 0` (`√η` has no derivative at 0). `ln a_j` moves the cumulative fractions
    /// `c_k = Σ_{i≤k} a_i`, `k ≥ j`, by `a_j`, so the rings' radii `r_k = √c_k` by `a_j/(2 r_k)`
    /// (concentric) or the wedges' edges `2π c_k` by `2π a_j` (sectors), each zone's inner and
    /// outer edge, and the order's efficiency `Σ a_k η_k` by `a_j η_j`; the fractions are free
    /// (`Σ a ≤ 1`, the rim beyond the zones opaque) except where they fill the aperture
    /// (`Σ a = 1`): there the last zone absorbs the change (`a_N = 1 − Σ_{k<N} a_k`, its outer
    /// edge held on the rim, `∂τ = a_j (η_j − η_N)`), and `None` for `a_N` itself (its growth
    /// would leave the aperture); `None` for a mask (its areas are measured, not parameters).
    fn zone_rates(&self, wavelength_m: f64, field: Field, key: ZoneKey) -> Option<Vec<ZoneRates>> {
        let n = self.channels.len();
        let f0 = self.focal_length;
        let mut zones = vec![ZoneRate::default(); n];
        let mut efficiency = 0.0;
        match key {
            ZoneKey::FieldAngle(axis) => {
                let theta = [field.x_rad, field.y_rad].get(axis).copied()?;
                let sec2 = 1.0 / (theta.cos() * theta.cos());
                for (z, c) in zones.iter_mut().zip(&self.channels) {
                    z.image_shift_m[axis] = f0 * sec2 * (c.wavelength_m / wavelength_m - 1.0);
                }
            }
            ZoneKey::ChannelWavelength(j) => {
                if j >= n || self.other_channels == OtherChannels::Background {
                    return None;
                }
                let lambda_j = self.channels[j].wavelength_m;
                let k = f0 / (8.0 * self.f_number * self.f_number);
                let lateral = f0 * lambda_j / wavelength_m;
                zones[j].defocus_m = k * wavelength_m / lambda_j;
                zones[j].image_shift_m = [lateral * field.x_rad.tan(), lateral * field.y_rad.tan()];
            }
            ZoneKey::ChannelEfficiency(j) => {
                if j >= n {
                    return None;
                }
                let (lo, hi) = self.bands[j];
                let lit = self.other_channels == OtherChannels::Signal || (wavelength_m >= lo && wavelength_m < hi);
                if lit {
                    let eta = self.channels[j].efficiency.value(wavelength_m);
                    if eta <= 0.0 {
                        return None;
                    }
                    zones[j].amplitude = 0.5 * eta.sqrt();
                    efficiency = self.areas[j] * eta;
                }
            }
            ZoneKey::AreaFraction(j) => {
                let areas = &self.areas;
                if j >= n || matches!(self.layout, Layout::Mask(_)) {
                    return None;
                }
                // a_j free (Σ a ≤ 1, the rim beyond the zones opaque); where the zones fill the
                // aperture the last absorbs the change, its outer edge on the rim: a_j alone
                // there would leave the aperture (refused for the last zone itself)
                let full = areas.iter().sum::<f64>() >= 1.0 - FILLED;
                if full && j + 1 == n {
                    return None;
                }
                let a_j = areas[j];
                // the cumulative fractions c_k = Σ_{i≤k} a_i and their rates ∂c_k/∂ln a_j
                let mut cumulative = 0.0;
                let mut c = Vec::with_capacity(n);
                for a in areas {
                    cumulative += a;
                    c.push(cumulative);
                }
                let dc: Vec<f64> = (0..n).map(|k| if k >= j && !(full && k + 1 == n) { a_j } else { 0.0 }).collect();
                for k in 0..n {
                    let below = if k == 0 { 0.0 } else { dc[k - 1] };
                    zones[k].edges = match self.layout {
                        // r_k = √c_k: ∂r_k = ∂c_k/(2 r_k)
                        Layout::Concentric => {
                            let rate = |i: usize, d: f64| if d == 0.0 { 0.0 } else { d / (2.0 * c[i].sqrt()) };
                            [if k == 0 { 0.0 } else { rate(k - 1, below) }, rate(k, dc[k]), 0.0, 0.0]
                        }
                        // the wedge [2π c_{k−1}, 2π c_k]
                        _ => [0.0, 0.0, TAU * below, TAU * dc[k]],
                    };
                }
                let eta = |k: usize| self.signal_eta(k, wavelength_m, self.other_channels);
                efficiency = a_j * (eta(j) - if full { eta(n - 1) } else { 0.0 });
            }
        }
        Some(vec![ZoneRates { zones, efficiency }])
    }

    fn transmission(&self, wavelength_m: f64) -> f64 {
        self.transmission.value(wavelength_m)
    }

    /// The centre of the channels' range, `(λ_min + λ_max)/2`.
    fn design_wavelength(&self) -> Option<f64> {
        Some(self.centre())
    }

    /// The curves' samples, and with [`OtherChannels::Background`] the band edges.
    /// With some table: one part where every channel has the same efficiency curve (its table
    /// scales each zone's field by `√t`, so the composite pupil's OTF × efficiency by `t`); with
    /// [`OtherChannels::Background`], where at each wavelength only one zone is lit, one part
    /// per channel whose efficiency is a table (the lens with only that zone lit, efficiency 1).
    /// `None` where channels of different efficiency curves are all signal: the coherent zone
    /// sum mixes them as `√(η_j η_k)`, which no table factors, and the rows then cut the
    /// spectral panels.
    fn factored_efficiency(&self) -> Option<optics::FactoredEfficiency> {
        let first = &self.channels[0].efficiency;
        let rebuilt = |efficiencies: &dyn Fn(usize) -> Curve| Segmented {
            channels: (0..self.channels.len())
                .map(|j| Channel { wavelength_m: self.channels[j].wavelength_m, efficiency: efficiencies(j) })
                .collect(),
            transmission: Curve::Constant(1.0),
            ..self.clone()
        };
        if self.channels.iter().all(|c| c.efficiency == *first) {
            return crate::chromatic::factor_one_curve(first, &self.transmission, 1.0, |efficiency, _| {
                Arc::new(rebuilt(&|_| efficiency.clone()))
            });
        }
        if self.other_channels != OtherChannels::Background {
            return None;
        }
        let parts = (0..self.channels.len())
            .map(|j| optics::FactoredPart {
                table: crate::chromatic::curve_spectrum(1.0, &self.channels[j].efficiency),
                relative: Arc::new(rebuilt(&|k| Curve::Constant(if k == j { 1.0 } else { 0.0 }))),
            })
            .collect();
        Some(optics::FactoredEfficiency {
            parts,
            transmission: crate::chromatic::curve_spectrum(1.0, &self.transmission),
        })
    }

    fn breakpoints(&self) -> Vec<f64> {
        let edges: Vec<f64> = if self.other_channels == OtherChannels::Background {
            self.bands.iter().flat_map(|&(lo, hi)| [lo, hi]).filter(|l| l.is_finite() && *l > 0.0).collect()
        } else {
            Vec::new()
        };
        crate::interleaved::channel_breakpoints(&self.channels, &self.transmission, edges)
    }

    fn describe(&self) -> String {
        let r = optics::round_for_display;
        let waves: Vec<String> = self.channels.iter().map(|c| format!("{}", r(c.wavelength_m * 1e9))).collect();
        let layout = match self.layout {
            Layout::Concentric => "concentric",
            Layout::Sectors => "sectors",
            Layout::Mask(_) => "mask",
        };
        format!(
            "segmented multiplexed metalens F/{} f0 = {} mm, {} channel{} at {} nm ({layout}{})",
            r(self.f_number),
            r(self.focal_length * 1e3),
            self.channels.len(),
            if self.channels.len() == 1 { "" } else { "s" },
            waves.join(", "),
            if self.other_channels == OtherChannels::Background { ", other channels as background" } else { "" }
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const F0: f64 = 3.36e-3;

    fn channels(waves_nm: &[f64], eta: f64) -> Vec<Channel> {
        waves_nm.iter().map(|&w| Channel { wavelength_m: w * 1e-9, efficiency: Curve::Constant(eta) }).collect()
    }

    fn rgb(layout: Layout) -> Segmented {
        Segmented::new(2.5, F0, channels(&[450.0, 550.0, 650.0], 0.8), layout, None, Curve::Constant(0.9)).unwrap()
    }

    #[test]
    fn zones_have_their_area_fractions() {
        // sectors and rings of 1/3 each, exact
        for layout in [Layout::Sectors, Layout::Concentric] {
            for a in rgb(layout).area_fractions() {
                assert!((a - 1.0 / 3.0).abs() < 1e-15, "{a}");
            }
        }
        // unequal areas and an opaque remainder
        let lens = Segmented::new(
            2.5,
            F0,
            channels(&[500.0, 600.0], 0.5),
            Layout::Sectors,
            Some(vec![0.5, 0.25]),
            Curve::Constant(0.9),
        )
        .unwrap();
        assert_eq!(lens.area_fractions(), &[0.5, 0.25]);
        assert!((lens.efficiency(550e-9) - 0.75 * 0.5).abs() < 1e-15);
    }

    #[test]
    fn one_order_whose_zones_carry_the_efficiencies() {
        let lens = rgb(Layout::Sectors);
        let orders = lens.orders(520e-9, Field::ON_AXIS);
        assert_eq!(orders.len(), 1);
        let o = &orders[0];
        assert!((o.efficiency - 0.8).abs() < 1e-15);
        assert!((o.pupil.area_fraction() - o.efficiency).abs() < 1e-15);
        let Pupil::Zones(zones) = &o.pupil else { panic!("a composite pupil") };
        let k = F0 / 50.0;
        for (j, z) in zones.iter().enumerate() {
            assert!((z.amplitude - 0.8f64.sqrt()).abs() < 1e-15);
            let want = (1.0 - 520e-9 / lens.channels()[j].wavelength_m) * k;
            assert!((z.wavefront.defocus_m - want).abs() < 1e-20, "{j}");
            // the apertures are built once
            assert!(Arc::ptr_eq(&z.aperture, &lens.zones[j]));
        }
        // the largest zone defocus: the 650 nm channel's, positive (its focal length at 520 nm,
        // f0 · 650/520, puts the focus behind the detector)
        assert_eq!(o.wavefront.defocus_m, lens.zone_defocus(2, 520e-9));
        assert!(o.wavefront.defocus_m > 0.0);
        let again = lens.orders(600e-9, Field::ON_AXIS);
        let Pupil::Zones(z2) = &again[0].pupil else { panic!() };
        assert!(Arc::ptr_eq(&zones[1].aperture, &z2[1].aperture));
    }

    #[test]
    fn off_axis_each_zone_has_its_lateral_colour() {
        let lens = rgb(Layout::Concentric);
        let field = Field::new(0.1, 0.0);
        let [o] = &lens.orders(550e-9, field)[..] else { panic!() };
        let Pupil::Zones(zones) = &o.pupil else { panic!() };
        let h0 = F0 * 0.1f64.tan();
        for (j, z) in zones.iter().enumerate() {
            let want = h0 * (lens.channels()[j].wavelength_m / 550e-9 - 1.0);
            assert!((z.wavefront.image_shift_m[0] - want).abs() < 1e-18 && z.wavefront.image_shift_m[1] == 0.0);
        }
        assert_eq!(zones[1].wavefront.image_shift_m, [0.0, 0.0]);
        assert_eq!(o.wavefront.image_shift_m, [0.0, 0.0]);
    }

    /// `zone_rates` against central differences of the lens's own orders (the slow, obviously
    /// correct reference): each zone's amplitude, defocus and image shift and the order's
    /// efficiency, per radian of a field angle, per ln λ_j and per ln η_j.
    #[test]
    fn zone_rates_match_differences_of_the_orders() {
        let (lambda, theta) = (540e-9, [0.03, -0.02]);
        // (zones' (amplitude, W020, shift), efficiency) of a sectors lens
        let at = |theta: [f64; 2], waves: [f64; 3], etas: [f64; 3]| {
            let channels = waves
                .iter()
                .zip(etas)
                .map(|(&w, eta)| Channel { wavelength_m: w, efficiency: Curve::Constant(eta) })
                .collect();
            let lens = Segmented::new(2.5, F0, channels, Layout::Sectors, None, Curve::Constant(0.9)).unwrap();
            let [o] = &lens.orders(lambda, Field::new(theta[0], theta[1]))[..] else { panic!() };
            let Pupil::Zones(zones) = &o.pupil else { panic!() };
            let z: Vec<[f64; 4]> = zones
                .iter()
                .map(|z| {
                    let [sx, sy] = z.wavefront.image_shift_m;
                    [z.amplitude, z.wavefront.defocus_m, sx, sy]
                })
                .collect();
            (z, o.efficiency)
        };
        let (waves, etas) = ([500e-9, 550e-9, 600e-9], [0.2, 0.3, 0.25]);
        let lens = {
            let channels = waves
                .iter()
                .zip(etas)
                .map(|(&w, eta)| Channel { wavelength_m: w, efficiency: Curve::Constant(eta) })
                .collect();
            Segmented::new(2.5, F0, channels, Layout::Sectors, None, Curve::Constant(0.9)).unwrap()
        };
        let field = Field::new(theta[0], theta[1]);
        let h = 1e-5;
        // each key: its rates, and the orders at its value ± h (per unit of the key)
        type Moved<'a> = Box<dyn Fn(f64) -> (Vec<[f64; 4]>, f64) + 'a>;
        let keys: Vec<(ZoneKey, Moved<'_>)> = vec![
            (ZoneKey::FieldAngle(0), Box::new(move |d| at([theta[0] + d, theta[1]], waves, etas))),
            (ZoneKey::FieldAngle(1), Box::new(move |d| at([theta[0], theta[1] + d], waves, etas))),
            (
                ZoneKey::ChannelWavelength(1),
                Box::new(move |d| at(theta, [waves[0], waves[1] * d.exp(), waves[2]], etas)),
            ),
            (ZoneKey::ChannelEfficiency(2), Box::new(move |d| at(theta, waves, [etas[0], etas[1], etas[2] * d.exp()]))),
        ];
        for (key, moved) in keys {
            let [r] = &lens.zone_rates(lambda, field, key).unwrap()[..] else { panic!() };
            let ((up, e_up), (down, e_down)) = (moved(h), moved(-h));
            for (j, z) in r.zones.iter().enumerate() {
                let ours = [z.amplitude, z.defocus_m, z.image_shift_m[0], z.image_shift_m[1]];
                for q in 0..4 {
                    let reference = (up[j][q] - down[j][q]) / (2.0 * h);
                    let scale = up[j][q].abs().max(reference.abs()).max(1e-12);
                    assert!(
                        (ours[q] - reference).abs() < 1e-7 * scale,
                        "{key:?} zone {j} [{q}]: {} vs {reference}",
                        ours[q]
                    );
                }
            }
            let reference = (e_up - e_down) / (2.0 * h);
            assert!((r.efficiency - reference).abs() < 1e-9, "{key:?}: {} vs {reference}", r.efficiency);
        }
        // λ_j with the other channels as background: refused (the band edges move with it)
        let background = lens.clone().with_other_channels(OtherChannels::Background);
        assert!(background.zone_rates(lambda, field, ZoneKey::ChannelWavelength(0)).is_none());
        assert!(background.zone_rates(lambda, field, ZoneKey::ChannelEfficiency(0)).is_some());
        assert!(lens.zone_rates(lambda, field, ZoneKey::ChannelEfficiency(3)).is_none());
    }

    #[test]
    fn background_keeps_only_the_channel_in_focus() {
        let lens = rgb(Layout::Sectors).with_other_channels(OtherChannels::Background);
        for (j, (lo, hi)) in [(400e-9, 500e-9), (500e-9, 600e-9), (600e-9, 700e-9)].into_iter().enumerate() {
            let (a, b) = lens.band(j);
            assert!((a - lo).abs() < 1e-20 && (b - hi).abs() < 1e-20, "{j}: {a} {b}");
        }
        for (lambda, lit) in
            [(420e-9, Some(0)), (501e-9, Some(1)), (599e-9, Some(1)), (690e-9, Some(2)), (701e-9, None)]
        {
            let o = &lens.orders(lambda, Field::ON_AXIS)[0];
            let Pupil::Zones(zones) = &o.pupil else { panic!() };
            for (j, z) in zones.iter().enumerate() {
                assert_eq!(z.amplitude > 0.0, lit == Some(j), "{lambda} zone {j}");
            }
            let want = if lit.is_some() { 0.8 / 3.0 } else { 0.0 };
            assert!((o.efficiency - want).abs() < 1e-15, "{lambda}");
            assert_eq!(lens.efficiency(lambda), o.efficiency);
            if let Some(j) = lit {
                assert_eq!(o.wavefront.defocus_m, lens.zone_defocus(j, lambda));
            }
            // the transmission does not change: the rest is background
            assert_eq!(lens.transmission(lambda), 0.9);
        }
        assert!(lens.breakpoints().iter().any(|b| (b - 500e-9).abs() < 1e-20), "{:?}", lens.breakpoints());
        // one channel: every wavelength is its band
        let one = Segmented::new(2.5, F0, channels(&[550.0], 0.5), Layout::Concentric, None, Curve::Constant(0.6))
            .unwrap()
            .with_other_channels(OtherChannels::Background);
        assert_eq!(one.efficiency(1000e-9), 0.5);
    }

    #[test]
    fn mask_layout_measures_its_zones() {
        // left half channel 0, right half channel 1
        let map: Arc<ZoneMap> = Arc::new(|x: f64, _y: f64| Some(if x < 0.0 { 0 } else { 1 }));
        let lens =
            Segmented::new(2.5, F0, channels(&[500.0, 600.0], 0.6), Layout::Mask(map), None, Curve::Constant(0.7))
                .unwrap();
        for a in lens.area_fractions() {
            assert!((a - 0.5).abs() < 1e-6, "{a}");
        }
        let bad: Arc<ZoneMap> = Arc::new(|x: f64, _y: f64| Some(if x < 0.0 { 0 } else { 2 }));
        let e = Segmented::new(2.5, F0, channels(&[500.0, 600.0], 0.6), Layout::Mask(bad), None, Curve::Constant(0.7))
            .unwrap_err();
        assert!(e.to_string().contains("mask zone index = 2"), "{e}");
        let empty: Arc<ZoneMap> = Arc::new(|_x: f64, _y: f64| Some(0));
        let e =
            Segmented::new(2.5, F0, channels(&[500.0, 600.0], 0.6), Layout::Mask(empty), None, Curve::Constant(0.7))
                .unwrap_err();
        assert!(e.to_string().contains("mask zone area = 0"), "{e}");
    }

    #[test]
    fn rejects_out_of_range_parameters() {
        let new = |waves: &[f64], eta: f64, areas: Option<Vec<f64>>, t: f64| {
            Segmented::new(2.5, F0, channels(waves, eta), Layout::Sectors, areas, Curve::Constant(t))
        };
        let e = new(&[], 0.5, None, 0.9).unwrap_err();
        assert!(e.to_string().contains("channels = 0 is out of range: expected 1 to 16"), "{e}");
        let e = new(&[500.0, 500.0], 0.5, None, 0.9).unwrap_err();
        assert!(e.to_string().contains("distinct channel wavelengths"), "{e}");
        let e = new(&[500.0, 600.0], 0.5, Some(vec![0.5, 0.0]), 0.9).unwrap_err();
        assert!(e.to_string().contains("area_fractions = 0 is out of range"), "{e}");
        let e = new(&[500.0, 600.0], 0.5, Some(vec![0.7, 0.4]), 0.9).unwrap_err();
        assert!(e.to_string().contains("area_fractions (sum) = 1.1"), "{e}");
        let e = new(&[500.0, 600.0], 0.5, Some(vec![0.5]), 0.9).unwrap_err();
        assert!(e.to_string().contains("one area fraction per channel"), "{e}");
        // Σ a_j η_j = 0.8 above T = 0.7
        let e = new(&[500.0, 600.0], 0.8, None, 0.7).unwrap_err();
        assert!(e.to_string().contains("exceeds transmission T = 0.7"), "{e}");
        let map: Arc<ZoneMap> = Arc::new(|_x: f64, _y: f64| Some(0));
        let e =
            Segmented::new(2.5, F0, channels(&[500.0], 0.5), Layout::Mask(map), Some(vec![1.0]), Curve::Constant(0.9))
                .unwrap_err();
        assert!(e.to_string().contains("none with a mask layout"), "{e}");
    }

    #[test]
    fn describes_itself() {
        assert_eq!(
            rgb(Layout::Concentric).describe(),
            "segmented multiplexed metalens F/2.5 f0 = 3.36 mm, 3 channels at 450, 550, 650 nm (concentric)"
        );
        assert_eq!(rgb(Layout::Sectors).kind(), "multiplexed-segmented");
    }
}
