//! The flat lens's exact pupil mapping (`[options] pupil_mapping = "exact"`, docs/physics.md,
//! "The flat lens's exact image"): any lens whose orders are radial pupils on its plane (a
//! phase profile, a meta-atom library) imaged through the direction cosines of its rays.

use std::sync::Arc;

use optics::radial::{DirectionCosines, RadialPupil};
use optics::{Field, LensModel, Order, Pupil, Wavefront};

use crate::Error;

/// `inner` imaged exactly on axis: each order through a radially symmetric pupil on the lens
/// plane ([`Pupil::Radial`], or the full aperture with a defocus) becomes its pupil in direction
/// cosines ([`DirectionCosines`]: the flat lens's map `sin θ = r/√(r² + f0²)`, the amplitude
/// divided by `cos²θ`, the cutoff `2 sin θ_max/λ`). Efficiency, transmission and the
/// radiometry's numerical aperture are the inner lens's (paraxial, eq. S7). On axis only: an
/// order of any other pupil, or off axis, is refused by [`ExactPupilMap::new`] at a probe
/// wavelength and left as it is at others (`scene` refuses the field and the families first).
#[derive(Debug)]
pub struct ExactPupilMap<L> {
    inner: L,
    map: Arc<DirectionCosines>,
    /// the mapped orders on axis by wavelength (its bits): an evaluation asks a wavelength's
    /// orders more than once, and the mapped pupils are prepared once
    cache: std::sync::Mutex<Vec<(u64, Vec<Order>)>>,
}

/// Wavelengths whose mapped orders a map keeps (as a library lens keeps its first orders).
const CACHE_WAVELENGTHS: usize = 4096;

/// Why the exact map refuses a lens: an order not a radially symmetric pupil on the lens plane.
const NOT_RADIAL: &str = "the exact pupil map takes orders that are radially symmetric pupils on the lens plane (a phase \
     profile, a meta-atom library's radial layout) with defocus as their only aberration";

/// Why [`ExactPupilMap::new`] would refuse `lens` (its orders at `probe_wavelength_m` on axis),
/// without mapping anything: `None` where every order is the full aperture or a radial pupil,
/// with no aberration beyond defocus, no image shift and no Zernike term off `m = 0` (the map is
/// radial on axis only). The pupil-mapping check of a paraxial report asks this first.
pub fn exact_map_refusal(lens: &dyn LensModel, probe_wavelength_m: f64) -> Option<&'static str> {
    let takes = |order: &Order| {
        let w = &order.wavefront;
        w.is_defocus_only()
            && w.image_shift_m == [0.0, 0.0]
            && match &order.pupil {
                Pupil::Radial(p) => p.is_symmetric(),
                Pupil::Full => true,
                _ => false,
            }
    };
    if lens.orders(probe_wavelength_m, Field::ON_AXIS).iter().all(takes) {
        return None;
    }
    let asymmetric = lens
        .orders(probe_wavelength_m, Field::ON_AXIS)
        .iter()
        .any(|o| matches!(&o.pupil, Pupil::Radial(p) if !p.is_symmetric()));
    Some(if asymmetric {
        "the exact pupil map is radial on axis only, and this lens's pupil has Zernike terms that are not \
         radially symmetric (m ≠ 0)"
    } else {
        NOT_RADIAL
    })
}

impl<L: LensModel> ExactPupilMap<L> {
    /// `inner` with its radial pupils mapped to direction cosines; refused where an order of
    /// `inner` at `probe_wavelength_m` on axis is not a radially symmetric pupil without other
    /// aberrations than defocus.
    pub fn new(inner: L, probe_wavelength_m: f64) -> Result<Self, Error> {
        if let Some(why) = exact_map_refusal(&inner, probe_wavelength_m) {
            return Err(Error::Mapping(why.to_owned()));
        }
        let na0 = 0.5 / inner.f_number();
        let map = Arc::new(DirectionCosines::new(na0).map_err(Error::Pupil)?);
        let lens = ExactPupilMap { inner, map, cache: Default::default() };
        for order in lens.inner.orders(probe_wavelength_m, Field::ON_AXIS) {
            lens.map_order(&order).ok_or_else(|| Error::Mapping(NOT_RADIAL.to_owned()))?;
        }
        Ok(lens)
    }

    /// The map (its frequency scale `√(1 + NA0²)`).
    pub fn map(&self) -> &DirectionCosines {
        &self.map
    }

    fn map_order(&self, order: &Order) -> Option<Order> {
        let w = &order.wavefront;
        if !w.is_defocus_only() || w.image_shift_m != [0.0, 0.0] {
            return None;
        }
        let (pupil, own) = match &order.pupil {
            Pupil::Radial(p) => (p.as_ref().clone(), w.defocus_m - p.fitted_defocus_m()),
            Pupil::Full => (RadialPupil::default(), w.defocus_m),
            _ => return None,
        };
        let mapped = self.map.map(&pupil, own).ok()?;
        Some(Order::radial(order.efficiency, Arc::new(mapped), Wavefront::default()))
    }
}

impl<L: LensModel> LensModel for ExactPupilMap<L> {
    fn f_number(&self) -> f64 {
        self.inner.f_number()
    }

    fn focal_length(&self) -> f64 {
        self.inner.focal_length()
    }

    fn orders(&self, wavelength_m: f64, field: Field) -> Vec<Order> {
        let key = wavelength_m.to_bits();
        let on_axis = field.is_on_axis();
        if on_axis
            && let Ok(cache) = self.cache.lock()
            && let Some((_, orders)) = cache.iter().find(|c| c.0 == key)
        {
            return orders.clone();
        }
        let orders: Vec<Order> = self
            .inner
            .orders(wavelength_m, field)
            .into_iter()
            .map(|order| self.map_order(&order).unwrap_or(order))
            .collect();
        if on_axis && let Ok(mut cache) = self.cache.lock() {
            if cache.len() >= CACHE_WAVELENGTHS {
                cache.clear();
            }
            cache.push((key, orders.clone()));
        }
        orders
    }

    fn transmission(&self, wavelength_m: f64) -> f64 {
        self.inner.transmission(wavelength_m)
    }

    fn efficiency(&self, wavelength_m: f64) -> f64 {
        self.inner.efficiency(wavelength_m)
    }

    /// The inner lens's factoring, each part's relative lens mapped the same way.
    fn factored_efficiency(&self) -> Option<optics::FactoredEfficiency> {
        let mut factored = self.inner.factored_efficiency()?;
        for part in &mut factored.parts {
            part.relative = Arc::new(ExactPupilMap {
                inner: part.relative.clone(),
                map: self.map.clone(),
                cache: Default::default(),
            });
        }
        Some(factored)
    }

    /// The inner lens's directions read through the map (a coefficient's change of the
    /// lens-plane wavefront, at the same ray).
    fn binary2_directions(&self, wavelength_m: f64) -> Option<Vec<Vec<optics::radial::RadialProfile>>> {
        let inner = self.inner.binary2_directions(wavelength_m)?;
        Some(inner.into_iter().map(|order| order.into_iter().map(|p| self.map.profile(p)).collect()).collect())
    }

    fn breakpoints(&self) -> Vec<f64> {
        self.inner.breakpoints()
    }

    fn design_wavelength(&self) -> Option<f64> {
        self.inner.design_wavelength()
    }

    fn describe(&self) -> String {
        format!("{}, pupil mapped exactly (direction cosines)", self.inner.describe())
    }
}
