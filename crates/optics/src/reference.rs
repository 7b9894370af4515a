//! Slow, obviously correct reference for the defocus OTF, the polychromatic OTF and the mean MTF.
//!
//! Everything here is written for checking, not for speed, and is deliberately independent of the
//! fast path: it uses its own adaptive Gauss–Kronrod (G10–K21 and G30–K61, QUADPACK constants), the
//! `y` form of the OTF integral exactly as printed in `PHYSICS.md` ("Optics: the OTF"), and plain
//! nested adaptive quadrature over wavelength and spatial frequency.
//!
//! Units: SI throughout (metres, cycles per metre). Waves for defocus.
//!
//! * [`otf_defocus`]: `OTF(s, w) = 4/(π a) ∫_0^{√(1−s²)} sin[a(√(1−y²) − s)] dy`, `a = 8π w s`,
//!   evaluated as `(4/π) ∫ u sinc(a u) dy` with `u = √(1−y²) − s`, which is exact at `a = 0`
//!   (`MTF_0(s)`) with no cancellation.
//! * [`polychromatic_otf`]: `∫ ρ(λ) OTF(ν λ F#, w(λ)) dλ / ∫ ρ(λ) dλ` for a chromatic lens
//!   `f(λ) = f0 λ0/λ`, `w(λ) = (λ/λ0 − 1) f0 / (8 F#² λ)` (signed sum, PHYSICS.md).
//! * [`mean_mtf`]: `(1/ν_N) ∫_0^{ν_N} P(ν) |OTF_poly(ν)| dν` (paper eq. 1 without SNR0), with the
//!   integration range split at the sign changes of `OTF_poly`.

use std::cmp::Ordering;
use std::collections::BinaryHeap;
use std::f64::consts::PI;

// ---------------------------------------------------------------------------------------------
// Gauss–Kronrod rules (QUADPACK dqk21 / dqk61 constants, Piessens et al. 1983, computed by
// L. W. Fullerton with 80-digit arithmetic; checked by polynomial exactness in the tests)
// ---------------------------------------------------------------------------------------------

/// A Gauss–Kronrod pair on [-1, 1] in QUADPACK layout: `xgk` are the non-negative Kronrod
/// abscissae in descending order ending with 0; `xgk[1], xgk[3], …` are the Gauss abscissae (the
/// Gauss rule has an even number of points, so 0 is a Kronrod-only node); `wgk` are the Kronrod
/// weights matching `xgk`; `wg[j]` is the Gauss weight of `xgk[2j + 1]`.
#[derive(Debug, Clone, Copy)]
pub struct GaussKronrod {
    xgk: &'static [f64],
    wgk: &'static [f64],
    wg: &'static [f64],
}

impl GaussKronrod {
    /// Number of points of the Kronrod rule.
    pub fn points(&self) -> usize {
        2 * self.xgk.len() - 1
    }

    /// Nodes of the Kronrod rule mapped to `[a, b]`, ascending; only the first
    /// [`points`](Self::points) entries are used.
    fn nodes(&self, a: f64, b: f64) -> [f64; MAX_POINTS] {
        let m = self.xgk.len() - 1;
        let c = 0.5 * (a + b);
        let h = 0.5 * (b - a);
        let mut x = [0.0; MAX_POINTS];
        for j in 0..m {
            x[j] = c - h * self.xgk[j];
            x[2 * m - j] = c + h * self.xgk[j];
        }
        x[m] = c;
        x
    }

    /// Kronrod value, QUADPACK error estimate and rounding floor `50 ε ∫|f|` of one panel from
    /// the function values at [`nodes`](Self::nodes). The error estimate is never below the floor.
    fn estimate(&self, a: f64, b: f64, fx: &[f64]) -> (f64, f64, f64) {
        let m = self.xgk.len() - 1;
        let h = 0.5 * (b - a);
        let mut resk = self.wgk[m] * fx[m];
        let mut resabs = self.wgk[m] * fx[m].abs();
        let mut resg = 0.0;
        for j in 0..m {
            let pair = fx[j] + fx[2 * m - j];
            resk += self.wgk[j] * pair;
            resabs += self.wgk[j] * (fx[j].abs() + fx[2 * m - j].abs());
            if j % 2 == 1 {
                resg += self.wg[j / 2] * pair;
            }
        }
        let mean = 0.5 * resk;
        let mut resasc = self.wgk[m] * (fx[m] - mean).abs();
        for j in 0..m {
            resasc += self.wgk[j] * ((fx[j] - mean).abs() + (fx[2 * m - j] - mean).abs());
        }
        let (resk, resabs, resasc) = (resk * h, resabs * h.abs(), resasc * h.abs());
        let mut err = (resk - resg * h).abs();
        if resasc != 0.0 && err != 0.0 {
            err = resasc * (200.0 * err / resasc).powf(1.5).min(1.0);
        }
        let mut round = 0.0;
        if resabs > f64::MIN_POSITIVE / (50.0 * f64::EPSILON) {
            round = 50.0 * f64::EPSILON * resabs;
            err = err.max(round);
        }
        (resk, err, round)
    }

    /// One panel: `(integral estimate, QUADPACK error estimate)` of `f` over `[a, b]`.
    pub fn panel<F: FnMut(f64) -> f64>(&self, mut f: F, a: f64, b: f64) -> (f64, f64) {
        let n = self.points();
        let x = self.nodes(a, b);
        let mut fx = [0.0; MAX_POINTS];
        for k in 0..n {
            fx[k] = f(x[k]);
        }
        let (value, error, _) = self.estimate(a, b, &fx[..n]);
        (value, error)
    }
}

/// Largest number of points of the rules below.
const MAX_POINTS: usize = 61;

/// The G10–K21 pair (QUADPACK `dqk21`).
// The 33-digit QUADPACK values are kept as published (rounded to f64 by the compiler).
#[allow(clippy::excessive_precision)]
pub const GK21: GaussKronrod = GaussKronrod {
    xgk: &[
        0.995_657_163_025_808_080_735_527_280_689_003,
        0.973_906_528_517_171_720_077_964_012_084_452,
        0.930_157_491_355_708_226_001_207_180_059_508,
        0.865_063_366_688_984_510_732_096_688_423_493,
        0.780_817_726_586_416_897_063_717_578_345_042,
        0.679_409_568_299_024_406_234_327_365_114_874,
        0.562_757_134_668_604_683_339_000_099_272_694,
        0.433_395_394_129_247_190_799_265_943_165_784,
        0.294_392_862_701_460_198_131_126_603_103_866,
        0.148_874_338_981_631_210_884_826_001_129_720,
        0.0,
    ],
    wgk: &[
        0.011_694_638_867_371_874_278_064_396_062_192,
        0.032_558_162_307_964_727_478_818_972_459_390,
        0.054_755_896_574_351_996_031_381_300_244_580,
        0.075_039_674_810_919_952_767_043_140_916_190,
        0.093_125_454_583_697_605_535_065_465_083_366,
        0.109_387_158_802_297_641_899_210_590_325_805,
        0.123_491_976_262_065_851_077_958_109_831_074,
        0.134_709_217_311_473_325_928_054_001_771_707,
        0.142_775_938_577_060_080_797_094_273_138_717,
        0.147_739_104_901_338_491_374_841_515_972_068,
        0.149_445_554_002_916_905_664_936_468_389_821,
    ],
    wg: &[
        0.066_671_344_308_688_137_593_568_809_893_332,
        0.149_451_349_150_580_593_145_776_339_657_697,
        0.219_086_362_515_982_043_995_534_934_228_163,
        0.269_266_719_309_996_355_091_226_921_569_469,
        0.295_524_224_714_752_870_173_892_994_651_338,
    ],
};

/// The G30–K61 pair (QUADPACK `dqk61`).
// The 33-digit QUADPACK values are kept as published (rounded to f64 by the compiler).
#[allow(clippy::excessive_precision)]
pub const GK61: GaussKronrod = GaussKronrod {
    xgk: &[
        0.999_484_410_050_490_637_571_325_895_705_811,
        0.996_893_484_074_649_540_271_630_050_918_695,
        0.991_630_996_870_404_594_858_628_366_109_486,
        0.983_668_123_279_747_209_970_032_581_605_663,
        0.973_116_322_501_126_268_374_693_868_423_707,
        0.960_021_864_968_307_512_216_871_025_581_798,
        0.944_374_444_748_559_979_415_831_324_037_439,
        0.926_200_047_429_274_325_879_324_277_080_474,
        0.905_573_307_699_907_798_546_522_558_925_958,
        0.882_560_535_792_052_681_543_116_462_530_226,
        0.857_205_233_546_061_098_958_658_510_658_944,
        0.829_565_762_382_768_397_442_898_119_732_502,
        0.799_727_835_821_839_083_013_668_942_322_683,
        0.767_777_432_104_826_194_917_977_340_974_503,
        0.733_790_062_453_226_804_726_171_131_369_528,
        0.697_850_494_793_315_796_932_292_388_026_640,
        0.660_061_064_126_626_961_370_053_668_149_271,
        0.620_526_182_989_242_861_140_477_556_431_189,
        0.579_345_235_826_361_691_756_024_932_172_540,
        0.536_624_148_142_019_899_264_169_793_311_073,
        0.492_480_467_861_778_574_993_693_061_207_709,
        0.447_033_769_538_089_176_780_609_900_322_854,
        0.400_401_254_830_394_392_535_476_211_542_661,
        0.352_704_725_530_878_113_471_037_207_089_374,
        0.304_073_202_273_625_077_372_677_107_199_257,
        0.254_636_926_167_889_846_439_805_129_817_805,
        0.204_525_116_682_309_891_438_957_671_002_025,
        0.153_869_913_608_583_546_963_794_672_743_256,
        0.102_806_937_966_737_030_147_096_751_318_001,
        0.051_471_842_555_317_695_833_025_213_166_723,
        0.0,
    ],
    wgk: &[
        0.001_389_013_698_677_007_624_551_591_226_760,
        0.003_890_461_127_099_884_051_267_201_844_516,
        0.006_630_703_915_931_292_173_319_826_369_750,
        0.009_273_279_659_517_763_428_441_146_892_024,
        0.011_823_015_253_496_341_742_232_898_853_251,
        0.014_369_729_507_045_804_812_451_432_443_580,
        0.016_920_889_189_053_272_627_572_289_420_322,
        0.019_414_141_193_942_381_173_408_951_050_128,
        0.021_828_035_821_609_192_297_167_485_738_339,
        0.024_191_162_078_080_601_365_686_370_725_232,
        0.026_509_954_882_333_101_610_601_709_335_075,
        0.028_754_048_765_041_292_843_978_785_354_334,
        0.030_907_257_562_387_762_472_884_252_943_092,
        0.032_981_447_057_483_726_031_814_191_016_854,
        0.034_979_338_028_060_024_137_499_670_731_468,
        0.036_882_364_651_821_229_223_911_065_617_136,
        0.038_678_945_624_727_592_950_348_651_532_281,
        0.040_374_538_951_535_959_111_995_279_752_468,
        0.041_969_810_215_164_246_147_147_541_285_970,
        0.043_452_539_701_356_069_316_831_728_117_073,
        0.044_814_800_133_162_663_192_355_551_616_723,
        0.046_059_238_271_006_988_116_271_735_559_374,
        0.047_185_546_569_299_153_945_261_478_181_099,
        0.048_185_861_757_087_129_140_779_492_298_305,
        0.049_055_434_555_029_778_887_528_165_367_238,
        0.049_795_683_427_074_206_357_811_569_379_942,
        0.050_405_921_402_782_346_840_893_085_653_585,
        0.050_881_795_898_749_606_492_297_473_049_805,
        0.051_221_547_849_258_772_170_656_282_604_944,
        0.051_426_128_537_459_025_933_862_879_215_781,
        0.051_494_729_429_451_567_558_340_433_647_099,
    ],
    wg: &[
        0.007_968_192_496_166_605_615_465_883_474_674,
        0.018_466_468_311_090_959_142_302_131_912_047,
        0.028_784_707_883_323_369_349_719_179_611_292,
        0.038_799_192_569_627_049_596_801_936_446_348,
        0.048_402_672_830_594_052_902_938_140_422_808,
        0.057_493_156_217_619_066_481_721_689_402_056,
        0.065_974_229_882_180_495_128_128_515_115_962,
        0.073_755_974_737_705_206_268_243_850_022_191,
        0.080_755_895_229_420_215_354_694_938_460_530,
        0.086_899_787_201_082_979_802_387_530_715_126,
        0.092_122_522_237_786_128_717_632_707_087_619,
        0.096_368_737_174_644_259_639_468_626_351_810,
        0.099_593_420_586_795_267_062_780_282_103_569,
        0.101_762_389_748_405_504_596_428_952_168_554,
        0.102_852_652_893_558_840_341_285_636_705_415,
    ],
};

/// Maximum number of bisections of an initial interval in [`integrate`].
pub const MAX_DEPTH: u32 = 60;

/// Maximum number of live panels in one adaptive integration (a safety stop).
const MAX_PANELS: usize = 500_000;

/// Result of an adaptive quadrature.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quadrature {
    /// The integral estimate (sum of the Kronrod results of all final panels).
    pub value: f64,
    /// Estimated absolute error (sum of the QUADPACK error estimates of all final panels).
    pub error: f64,
    /// Number of integrand evaluations.
    pub evaluations: usize,
    /// Whether the summed error estimate meets the requested tolerance.
    pub converged: bool,
}

/// A panel of the globally adaptive scheme, ordered by its error estimate.
#[derive(Debug, Clone, Copy)]
struct Panel {
    a: f64,
    b: f64,
    value: f64,
    error: f64,
    depth: u32,
    /// Rounding floor `50 ε ∫|f|` of the panel; a panel whose error estimate is no larger (or
    /// zero) is never bisected, since bisection cannot reduce it.
    round: f64,
}

impl PartialEq for Panel {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Panel {}
impl PartialOrd for Panel {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Panel {
    fn cmp(&self, other: &Self) -> Ordering {
        self.error.total_cmp(&other.error)
    }
}

/// Whether `[a, b]` can still be bisected in floating point.
fn splittable(p: &Panel) -> bool {
    let m = 0.5 * (p.a + p.b);
    p.error > p.round && p.depth < MAX_DEPTH && m > p.a && m < p.b
}

/// Globally adaptive bisection over a list of panels (QUADPACK QAG strategy): repeatedly bisect the
/// panel with the largest error estimate until `Σ error ≤ max(abs_tol, rel_tol |Σ value|)`.
/// `eval(a, b, depth)` returns the panels that replace `[a, b]` (normally one).
fn adapt<E: FnMut(f64, f64, u32) -> Vec<Panel>>(
    initial: Vec<Panel>,
    mut eval: E,
    abs_tol: f64,
    rel_tol: f64,
    evaluations: &dyn Fn() -> usize,
) -> Quadrature {
    let mut heap: BinaryHeap<Panel> = BinaryHeap::new();
    let mut frozen: Vec<Panel> = Vec::new();
    for p in initial {
        if splittable(&p) {
            heap.push(p);
        } else {
            frozen.push(p);
        }
    }
    let sums = |heap: &BinaryHeap<Panel>, frozen: &[Panel]| {
        let (mut v, mut e, mut r) = (0.0, 0.0, 0.0);
        for p in heap.iter().chain(frozen.iter()) {
            v += p.value;
            e += p.error;
            r += p.round;
        }
        (v, e, r)
    };
    // Done when the target is met, or when the error is within twice the summed rounding floors
    // (a target below rounding cannot be met; bisecting further would only chase noise).
    let done = |v: f64, e: f64, r: f64| e <= abs_tol.max(rel_tol * v.abs()).max(2.0 * r);
    let (mut value, mut error, mut round) = sums(&heap, &frozen);
    loop {
        if done(value, error, round) {
            // Re-sum exactly to remove drift of the running sums before accepting.
            (value, error, round) = sums(&heap, &frozen);
            if done(value, error, round) {
                break;
            }
        }
        let Some(worst) = heap.pop() else {
            break;
        };
        if heap.len() + frozen.len() > MAX_PANELS {
            heap.push(worst);
            break;
        }
        let m = 0.5 * (worst.a + worst.b);
        let mut children = eval(worst.a, m, worst.depth + 1);
        children.extend(eval(m, worst.b, worst.depth + 1));
        value -= worst.value;
        error -= worst.error;
        round -= worst.round;
        for c in children {
            value += c.value;
            error += c.error;
            round += c.round;
            if splittable(&c) {
                heap.push(c);
            } else {
                frozen.push(c);
            }
        }
    }
    let (value, error, _) = sums(&heap, &frozen);
    Quadrature { value, error, evaluations: evaluations(), converged: error <= abs_tol.max(rel_tol * value.abs()) }
}

/// Adaptive Gauss–Kronrod quadrature of `f` from the smallest to the largest of `points`,
/// integrating piecewise between all of them (any order, duplicates allowed).
///
/// Globally adaptive bisection (QUADPACK QAG): the panel with the largest error estimate is
/// bisected until the summed QUADPACK error estimate is at most `max(abs_tol, rel_tol |value|)`.
/// Panels at [`MAX_DEPTH`] bisections, too narrow to split, or whose estimate is already the
/// rounding floor `50 ε ∫|f|` are not split, and the work stops when the summed estimate is within
/// twice the summed rounding floors; `converged` says whether the target itself was met.
pub fn integrate<F: FnMut(f64) -> f64>(
    rule: GaussKronrod,
    f: F,
    points: &[f64],
    abs_tol: f64,
    rel_tol: f64,
) -> Quadrature {
    let pts = sorted_points(points);
    let count = std::cell::Cell::new(0usize);
    let f = std::cell::RefCell::new(f);
    let eval = |a: f64, b: f64, depth: u32| {
        let n = rule.points();
        let x = rule.nodes(a, b);
        let mut fx = [0.0; MAX_POINTS];
        let mut g = f.borrow_mut();
        for k in 0..n {
            fx[k] = (*g)(x[k]);
        }
        count.set(count.get() + n);
        let (value, error, round) = rule.estimate(a, b, &fx[..n]);
        vec![Panel { a, b, value, error, depth, round }]
    };
    let mut initial = Vec::new();
    for w in pts.windows(2) {
        initial.extend(eval(w[0], w[1], 0));
    }
    adapt(initial, eval, abs_tol, rel_tol, &|| count.get())
}

/// Smallest absolute tolerance (normalized OTF units) requested from the spectral integral: the
/// OTF itself is only accurate to about 1e-14 (rounding), and asking the spectral quadrature to
/// resolve noise of that size would make it bisect without end.
const MIN_POLY_TOL: f64 = 2e-13;

/// Finite breakpoints, sorted ascending, without duplicates.
fn sorted_points(points: &[f64]) -> Vec<f64> {
    let mut pts: Vec<f64> = points.iter().copied().filter(|x| x.is_finite()).collect();
    pts.sort_by(f64::total_cmp);
    pts.dedup();
    pts
}

/// First pair of indices `i < j` with `fx[i]`, `fx[j]` of opposite signs and only zeros between.
fn sign_change(fx: &[f64]) -> Option<(usize, usize)> {
    let mut last: Option<usize> = None;
    for (j, &v) in fx.iter().enumerate() {
        if v != 0.0 {
            if let Some(i) = last
                && (fx[i] > 0.0) != (v > 0.0)
            {
                return Some((i, j));
            }
            last = Some(j);
        }
    }
    None
}

/// Root of `f` in `(x0, x1)` given `f(x0) = f0`, `f(x1) = f1` of opposite signs, by the Illinois
/// (modified regula falsi) method, which keeps the root bracketed. Stops at bracket width `xtol`.
fn illinois<F: FnMut(f64) -> f64>(f: &mut F, mut x0: f64, mut f0: f64, mut x1: f64, mut f1: f64, xtol: f64) -> f64 {
    let mut side = 0;
    for _ in 0..200 {
        if (x1 - x0).abs() <= xtol {
            break;
        }
        let mut x = (x0 * f1 - x1 * f0) / (f1 - f0);
        if !(x > x0.min(x1) && x < x0.max(x1)) {
            x = 0.5 * (x0 + x1);
        }
        let fx = f(x);
        if fx == 0.0 {
            return x;
        }
        if (fx > 0.0) == (f1 > 0.0) {
            x1 = x;
            f1 = fx;
            if side == -1 {
                f0 *= 0.5;
            }
            side = -1;
        } else {
            x0 = x;
            f0 = fx;
            if side == 1 {
                f1 *= 0.5;
            }
            side = 1;
        }
    }
    if f0.abs() < f1.abs() { x0 } else { x1 }
}

/// Adaptive quadrature of `weight(x) |f(x)|`, split at the sign changes of `f`.
///
/// The nodes of every panel are checked for a sign change of `f`; where one is found the root is
/// located (Illinois, to `1e-13` of the whole range) and the panel replaced by the two panels on
/// either side of it, so that `|f|` is smooth on the panels that are kept. Sign changes that fall
/// between nodes are still handled correctly, only more slowly: the kink makes the error estimate
/// large and the panel is bisected until its nodes see the change. Otherwise as [`integrate`].
pub fn integrate_modulus<F: FnMut(f64) -> f64, P: Fn(f64) -> f64>(
    rule: GaussKronrod,
    f: F,
    weight: P,
    points: &[f64],
    abs_tol: f64,
    rel_tol: f64,
) -> Quadrature {
    let pts = sorted_points(points);
    let span = pts.last().copied().unwrap_or(0.0) - pts.first().copied().unwrap_or(0.0);
    let xtol = 1e-13 * span.abs();
    let count = std::cell::Cell::new(0usize);
    let f = std::cell::RefCell::new(f);
    let eval = |a: f64, b: f64, depth: u32| {
        let mut out = Vec::new();
        let mut todo = vec![(a, b, depth)];
        while let Some((a, b, depth)) = todo.pop() {
            let n = rule.points();
            let x = rule.nodes(a, b);
            let mut fx = [0.0; MAX_POINTS];
            let mut g = f.borrow_mut();
            for k in 0..n {
                fx[k] = (*g)(x[k]);
            }
            count.set(count.get() + n);
            if depth < MAX_DEPTH
                && let Some((i, j)) = sign_change(&fx[..n])
            {
                let mut counted = |t: f64| {
                    count.set(count.get() + 1);
                    (*g)(t)
                };
                let r = illinois(&mut counted, x[i], fx[i], x[j], fx[j], xtol);
                if r > a && r < b {
                    todo.push((a, r, depth + 1));
                    todo.push((r, b, depth + 1));
                    continue;
                }
            }
            let gx: [f64; MAX_POINTS] = std::array::from_fn(|k| weight(x[k]) * fx[k].abs());
            let (value, error, round) = rule.estimate(a, b, &gx[..n]);
            out.push(Panel { a, b, value, error, depth, round });
        }
        out
    };
    let mut initial = Vec::new();
    for w in pts.windows(2) {
        initial.extend(eval(w[0], w[1], 0));
    }
    adapt(initial, eval, abs_tol, rel_tol, &|| count.get())
}

// ---------------------------------------------------------------------------------------------
// Monochromatic OTF of a defocused circular pupil
// ---------------------------------------------------------------------------------------------

/// Absolute accuracy target of [`otf_defocus`].
pub const OTF_ABS_TOL: f64 = 1e-13;

/// Initial panels per period of `sin(a u)` in the OTF integral when it has fewer than 8 periods
/// (G10–K21 panels of 1.3 periods).
const Y_PANELS_PER_PERIOD_21: f64 = 0.75;

/// Initial panels per period of `sin(a u)` in the OTF integral when it has 8 periods or more
/// (G30–K61 panels of 10 periods).
const Y_PANELS_PER_PERIOD_61: f64 = 0.1;

/// Initial panels per period (`Δa = 2π`) of the OTF's oscillation in λ (G10–K21 panels of 2
/// periods). These only set the starting mesh: adaptivity refines wherever it is too coarse.
const LAMBDA_PANELS_PER_PERIOD: f64 = 0.5;

/// `sin(x)/x`, equal to 1 at `x = 0`. (`sin` has full relative accuracy, so no series is needed.)
fn sinc(x: f64) -> f64 {
    if x == 0.0 { 1.0 } else { x.sin() / x }
}

/// PHYSICS.md test vectors `(s, w, OTF)` for the defocused OTF, printed there to 5 decimals
/// (tolerance 1e-5): every OTF implementation is checked against them.
pub const PHYSICS_TEST_VECTORS: [(f64, f64, f64); 7] = [
    (0.1, 0.0, 0.87289),
    (0.1, 0.5, 0.74209),
    (0.1, 1.0, 0.42665),
    (0.2, 1.0, -0.01441),
    (0.5, 0.25, 0.28747),
    (0.05, 2.0, 0.41297),
    (0.1, 2.0, -0.08396),
];

/// Exact OTF of a circular pupil with defocus `w` (waves at the pupil edge) at normalized
/// frequency `s = ν/ν_c`, from PHYSICS.md as printed:
/// `OTF(s, w) = 4/(π a) ∫_0^{√(1−s²)} sin[a(√(1−y²) − s)] dy`, `a = 8π w s`,
/// computed as `(4/π) ∫ u sinc(a u) dy`, `u = √(1−y²) − s`, so that `a → 0` gives
/// `MTF_0(s) = (2/π)[acos s − s√(1−s²)]` without cancellation. Real, may be negative; even in `s`
/// and `w`; 1 at `s = 0`; 0 for `|s| ≥ 1`. Absolute accuracy about [`OTF_ABS_TOL`].
pub fn otf_defocus(s: f64, w: f64) -> f64 {
    otf_defocus_tol(s, w, OTF_ABS_TOL)
}

/// [`otf_defocus`] with a given absolute accuracy target.
fn otf_defocus_tol(s: f64, w: f64, abs_tol: f64) -> f64 {
    if s.is_nan() || w.is_nan() {
        return f64::NAN;
    }
    let s = s.abs();
    if s >= 1.0 {
        return 0.0;
    }
    if s == 0.0 {
        return 1.0;
    }
    let a = 8.0 * PI * w * s;
    let ymax = ((1.0 - s) * (1.0 + s)).sqrt();
    // Breakpoints, chosen in c = √(1−y²) ∈ [s, 1] and mapped to y = √(1−c²):
    // (i) equal steps of the phase a(c − s) (a few periods per panel at most, see the constants);
    // (ii) c = 2s, 4s, 8s, … grading towards the branch point of √(1−y²) at y = 1 (c = 0),
    //      which lies just beyond y_max when s is small.
    let periods = a.abs() * (1.0 - s) / (2.0 * PI);
    // Long oscillatory integrals: G30–K61 on panels of several periods; short ones: G10–K21.
    let (rule, per) = if periods >= 8.0 { (GK61, Y_PANELS_PER_PERIOD_61) } else { (GK21, Y_PANELS_PER_PERIOD_21) };
    let n = (periods * per).ceil().max(1.0) as usize;
    let mut cs: Vec<f64> = (1..n).map(|k| s + (1.0 - s) * k as f64 / n as f64).collect();
    let mut c = 2.0 * s;
    while c < 1.0 {
        cs.push(c);
        c *= 2.0;
    }
    let mut ys: Vec<f64> = cs.iter().map(|&c| ((1.0 - c) * (1.0 + c)).sqrt()).collect();
    ys.retain(|&y| y > 0.0 && y < ymax);
    ys.push(0.0);
    ys.push(ymax);
    let integrand = |y: f64| {
        let u = ((1.0 - y) * (1.0 + y)).sqrt() - s;
        if u <= 0.0 { 0.0 } else { u * sinc(a * u) }
    };
    let q = integrate(rule, integrand, &ys, abs_tol * PI / 4.0, 0.0);
    4.0 / PI * q.value
}

// ---------------------------------------------------------------------------------------------
// Polychromatic OTF and mean MTF of a chromatic (diffractive) lens
// ---------------------------------------------------------------------------------------------

/// A chromatic lens `f(λ) = f0 λ0/λ` with a detector at `f0`, a spectrum and a pixel pitch.
pub struct ReferenceScene<'a> {
    /// Photoelectron spectral density (arbitrary scale) at wavelength λ (m); zero outside
    /// `[lambda_min, lambda_max]`.
    pub density: &'a dyn Fn(f64) -> f64,
    /// Lower end of the wavelength integration range (m), `> 0`.
    pub lambda_min: f64,
    /// Upper end of the wavelength integration range (m), finite.
    pub lambda_max: f64,
    /// Wavelengths (m) inside the range where the density has kinks or jumps.
    pub breakpoints: &'a [f64],
    /// F-number `F# = f0/D`.
    pub f_number: f64,
    /// Design focal length `f0` (m); the detector stays at `f0`.
    pub focal_length_m: f64,
    /// Design wavelength `λ0` (m).
    pub design_wavelength_m: f64,
    /// Pixel pitch `p` (m); Nyquist `ν_N = 1/(2p)`.
    pub pixel_pitch_m: f64,
    /// Multiply the MTF by the pixel aperture MTF `|sinc(p ν)|` (100 % fill factor).
    pub pixel_mtf: bool,
}

impl ReferenceScene<'_> {
    /// Defocus at the pupil edge in waves, `w(λ) = (λ/λ0 − 1) f0 / (8 F#²) / λ`.
    pub fn defocus_waves(&self, lambda: f64) -> f64 {
        (lambda / self.design_wavelength_m - 1.0) * self.focal_length_m / (8.0 * self.f_number * self.f_number) / lambda
    }

    /// Nyquist frequency `ν_N = 1/(2p)` (cycles/m).
    pub fn nyquist(&self) -> f64 {
        0.5 / self.pixel_pitch_m
    }

    /// `∫ ρ(λ) dλ` over the range (64 panels per piece between breakpoints, relative 1e-14).
    fn norm(&self) -> f64 {
        let pts = self.lambda_points(self.lambda_min, self.lambda_max);
        let n = 64;
        let mut fine = Vec::new();
        for w in pts.windows(2) {
            fine.extend((0..n).map(|k| w[0] + (w[1] - w[0]) * k as f64 / n as f64));
        }
        fine.push(self.lambda_max);
        integrate(GK21, |l| (self.density)(l), &fine, 0.0, 1e-14).value
    }

    /// Breakpoints of the density inside `[lo, hi]`, with the ends.
    fn lambda_points(&self, lo: f64, hi: f64) -> Vec<f64> {
        let mut pts: Vec<f64> = self
            .breakpoints
            .iter()
            .copied()
            .chain(std::iter::once(self.design_wavelength_m))
            .filter(|&l| l > lo && l < hi)
            .collect();
        pts.push(lo);
        pts.push(hi);
        sorted_points(&pts)
    }

    /// `∫ ρ(λ) OTF(ν λ F#, w(λ)) dλ / norm` with absolute error about `tol`.
    fn poly_otf_abs(&self, nu: f64, tol: f64, norm: f64) -> f64 {
        let tol = tol.max(MIN_POLY_TOL);
        let nu = nu.abs();
        let fnum = self.f_number;
        let lo = self.lambda_min;
        // Past λ = 1/(ν F#) the frequency is beyond the cutoff and the OTF is zero.
        let hi = if nu > 0.0 { self.lambda_max.min(1.0 / (nu * fnum)) } else { self.lambda_max };
        if hi <= lo || norm == 0.0 {
            return 0.0;
        }
        // Initial panels of two periods of the OTF's oscillation in λ: a = 8π w s is linear in λ
        // with slope da/dλ = π ν f0/(F# λ0); at least 8 panels per piece.
        let slope = PI * nu * self.focal_length_m / (fnum * self.design_wavelength_m);
        let mut pts = Vec::new();
        for w in self.lambda_points(lo, hi).windows(2) {
            let periods = slope * (w[1] - w[0]) / (2.0 * PI);
            let n = ((periods * LAMBDA_PANELS_PER_PERIOD).ceil() as usize).max(8);
            pts.extend((0..n).map(|k| w[0] + (w[1] - w[0]) * k as f64 / n as f64));
        }
        pts.push(hi);
        // Error budget (normalized): quadrature 0.5 tol, OTF 0.2 tol, cut 0.05 tol. The cut is
        // rigorous: where ρ(λ) times a bound on |OTF| is ≤ θ, dropping the node changes the
        // integral by at most θ (hi − lo).
        let theta = 0.05 * tol * norm / (hi - lo);
        let otf_tol = 0.2 * tol;
        let integrand = |l: f64| {
            let r = (self.density)(l);
            let (s, w) = (nu * l * fnum, self.defocus_waves(l));
            // |OTF| ≤ min(1, 4/(π |a|)) from |sin| ≤ 1 in the printed formula (a = 8π w s).
            let bound = (4.0 / (PI * (8.0 * PI * w * s).abs())).min(1.0);
            if r.abs() * bound <= theta { 0.0 } else { r * otf_defocus_tol(s, w, otf_tol) }
        };
        let q = integrate(GK21, integrand, &pts, 0.5 * tol * norm, 0.0);
        q.value / norm
    }

    /// `∫_0^{ν_N} P(ν) |OTF_poly(ν)| dν` with OTF_poly accurate to `inner_tol` (absolute).
    fn modulus_integral(&self, rel_tol: f64, inner_tol: f64, norm: f64) -> Quadrature {
        let fnum = self.f_number;
        let nu_n = self.nyquist();
        let nu_hi = nu_n.min(1.0 / (self.lambda_min * fnum));
        // ν where the upper wavelength limit 1/(ν F#) crosses λ_max or a density breakpoint.
        let mut pts: Vec<f64> = self
            .breakpoints
            .iter()
            .chain(std::iter::once(&self.lambda_max))
            .map(|&l| 1.0 / (l * fnum))
            .filter(|&nu| nu > 0.0 && nu < nu_hi)
            .collect();
        pts.extend((0..=4).map(|k| nu_hi * k as f64 / 4.0));
        let p = self.pixel_pitch_m;
        let pixel = self.pixel_mtf;
        let weight = move |nu: f64| if pixel { sinc(PI * p * nu).abs() } else { 1.0 };
        integrate_modulus(
            GK21,
            |nu| self.poly_otf_abs(nu, inner_tol, norm),
            weight,
            &pts,
            0.1 * inner_tol * nu_n,
            rel_tol,
        )
    }
}

/// Polychromatic OTF `∫ ρ(λ) OTF(ν λ F#, w(λ)) dλ / ∫ ρ(λ) dλ` at frequency `nu` (cycles/m):
/// the signed, photoelectron-weighted sum of the monochromatic OTFs (PHYSICS.md
/// "Polychromatic OTF"). Error target `rel_tol · max(|OTF_poly|, 1e-3)`.
pub fn polychromatic_otf(scene: &ReferenceScene<'_>, nu: f64, rel_tol: f64) -> f64 {
    let norm = scene.norm();
    let rough = scene.poly_otf_abs(nu, 1e-6, norm);
    let tol = rel_tol * rough.abs().max(1e-3);
    scene.poly_otf_abs(nu, tol, norm)
}

/// Mean MTF up to Nyquist, `(1/ν_N) ∫_0^{ν_N} P(ν) |OTF_poly(ν)| dν` with
/// `P(ν) = |sin(π p ν)/(π p ν)|` if `pixel_mtf`, else 1 (paper eq. 1 divided by SNR0 ν_N).
/// Relative error target `rel_tol`, down to about `2e-12 / mean` (the inner integrals are not
/// asked for better than 2e-13 absolute). Measured cost (opt-level 2): 0.06 s for the paper scene
/// (F/2.5, 50 nm Gaussian, 5.2 µm), 2.3 s for F/1.4, 200 nm, 2 µm; nearly independent of
/// `rel_tol` because the oscillations must be resolved anyway.
pub fn mean_mtf(scene: &ReferenceScene<'_>, rel_tol: f64) -> f64 {
    mean_mtf_quadrature(scene, rel_tol).value
}

/// [`mean_mtf`] with the frequency quadrature's error estimate (divided by `ν_N`; the inner
/// integrals are held to a tenth of the target separately), its number of OTF_poly evaluations,
/// and whether it converged.
pub fn mean_mtf_quadrature(scene: &ReferenceScene<'_>, rel_tol: f64) -> Quadrature {
    let norm = scene.norm();
    let nu_n = scene.nyquist();
    // The inner (OTF_poly) error feeds straight into the mean: keep it below a tenth of the
    // target, assuming first that the mean is at least 1e-3 and redoing the work if it is not.
    let mut scale = 1e-3;
    loop {
        let q = scene.modulus_integral(0.5 * rel_tol, 0.1 * rel_tol * scale, norm);
        let m = q.value / nu_n;
        if m >= scale || m <= 0.0 || scale < 1e-12 {
            return Quadrature { value: m, error: q.error / nu_n, ..q };
        }
        scale = 0.5 * m;
    }
}

/// Hopkins' Bessel series for the defocused OTF (H. H. Hopkins, "The frequency response of a
/// defocused optical system", Proc. R. Soc. A 231, 91–103, 1955), a third independent evaluation.
///
/// In Hopkins' reduced frequency `s_H = 2s` (so `s_H = 2` is the cutoff) and with
/// `a = 4π w s_H = 8π w s`, `β = acos(s_H/2)`:
///
/// ```text
/// OTF = (4/(π a)) cos(a s_H/2) [β J1(a) + Σ_{n≥1} (−1)^{n+1} sin(2nβ)/(2n) (J_{2n−1}(a) − J_{2n+1}(a))]
///     − (4/(π a)) sin(a s_H/2) [Σ_{n≥0} (−1)^n sin((2n+1)β)/(2n+1) (J_{2n}(a) − J_{2n+2}(a))]
/// ```
///
/// Bessel functions from `libm::jn` (not the fast path's recurrence); the sums stop where
/// `Jn(a)` is below 1e-17 (`n > a + 12 a^{1/3} + 30`). For `a → 0` the closed form MTF_0 is used.
pub fn otf_hopkins(s: f64, w: f64) -> f64 {
    let a = (8.0 * PI * w * s).abs();
    otf_hopkins_terms(s, w, (a + 12.0 * a.cbrt() + 30.0) as usize + 1)
}

/// [`otf_hopkins`] with each of its two brackets cut after `terms` terms: `β J1` and `n = 1 …
/// terms − 1` in the first, `n = 0 … terms − 1` in the second (Bessel orders up to `2 terms`).
/// The series converges once `2 terms` passes `|a| = 8π |w s|`, where `Jn(a)` starts to decay;
/// fewer terms give the truncation error the accuracy report measures.
pub fn otf_hopkins_terms(s: f64, w: f64, terms: usize) -> f64 {
    if s <= 0.0 {
        return 1.0;
    }
    if s >= 1.0 {
        return 0.0;
    }
    let a = (8.0 * PI * w * s).abs();
    let beta = s.acos();
    if a < 1e-6 {
        return std::f64::consts::FRAC_2_PI * (beta - s * (1.0 - s * s).sqrt());
    }
    let j = |n: i32| libm::jn(n, a);
    let terms = i32::try_from(terms).unwrap_or(i32::MAX / 2 - 1);
    let mut first = beta * j(1);
    let mut second = 0.0;
    for n in 1..terms {
        let sign = if n % 2 == 1 { 1.0 } else { -1.0 };
        let m = f64::from(2 * n);
        first += sign * (m * beta).sin() / m * (j(2 * n - 1) - j(2 * n + 1));
    }
    for n in 0..terms {
        let sign = if n % 2 == 0 { 1.0 } else { -1.0 };
        let m = f64::from(2 * n + 1);
        second += sign * (m * beta).sin() / m * (j(2 * n) - j(2 * n + 2));
    }
    let k = 4.0 / (PI * a);
    k * ((a * s).cos() * first - (a * s).sin() * second)
}

/// The geometric-optics limit of the defocused OTF (PHYSICS.md, "Geometric limit"), an
/// approximation for comparisons, good at large defocus only: `OTF → 2 J1(x)/x` with
/// `x = π d ν`, blur-disk diameter `d = 2 |Δz| NA`. With `Δz = 8 F#² W020`, `NA = 1/(2 F#)` and
/// `ν = s/(λ F#)`, `x = 8π |w| s = |a|`. 1 at `s ≤ 0` and `a = 0`; 0 at `s ≥ 1` like the OTF
/// (the geometric formula itself knows no cutoff); `J1` from `libm`.
pub fn otf_geometric(s: f64, w: f64) -> f64 {
    if s <= 0.0 {
        return 1.0;
    }
    if s >= 1.0 {
        return 0.0;
    }
    let x = (8.0 * PI * w * s).abs();
    if x < 1e-8 { 1.0 - x * x / 8.0 } else { 2.0 * libm::j1(x) / x }
}
