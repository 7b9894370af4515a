//! A bounded quasi-Newton search: projected L-BFGS (limited-memory BFGS, Nocedal 1980; the
//! two-loop recursion of Nocedal & Wright, *Numerical Optimization*, 2nd ed., algorithm 7.4)
//! on a box, for tens of keys whose gradient is known.
//!
//! Each iteration fixes the keys at a bound whose gradient pushes them out of the box (the
//! binding set), takes the L-BFGS direction in the other keys, and searches along the
//! *projected* path `x(α) = P(x + α d)` (`P` clamps each key into its bounds) by backtracking
//! until the Armijo condition `f(x(α)) ≥ f(x) + c₁ ∇f·(x(α) − x)` holds (maximizing; Bertsekas,
//! *Nonlinear Programming*, 2nd ed., §2.3, the Armijo rule along the projection arc). Where the
//! quasi-Newton direction finds no such point, the memory is dropped and the projected gradient
//! is searched instead, whose arc is an ascent path for small α; where that fails too, the
//! objective's own rounding limits the step and the search stops. A curvature pair `(s, y)` is
//! kept only where `s·y` shows the negative curvature a maximum has (`−s·y > 0`), so the
//! inverse Hessian stays positive definite.
//!
//! The stationarity measure is the projected gradient `P(x + ∇f) − x` (zero at a maximum on the
//! box, whether inside or on a bound), reported as its largest component.

use anyhow::Result;

/// What the objective returns at a point: its value and gradient, or `None` where it refuses to
/// score the point.
pub type Scored = Option<(f64, Vec<f64>)>;

/// The sufficient-increase constant `c₁` of the Armijo condition.
const ARMIJO: f64 = 1e-4;

/// The most halvings of one line search.
const BACKTRACKS: usize = 50;

/// Settings of [`maximize`].
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    /// Curvature pairs kept (L-BFGS's memory).
    pub memory: usize,
    /// Stop when the projected gradient's largest component is at most this.
    pub gtol: f64,
    /// Stop when a step's largest component is at most this (the coordinates' units).
    pub xtol: f64,
    /// Stop when an iteration raises the objective by at most this fraction of its size.
    pub ftol: f64,
    /// The largest component of the first step (before any curvature is known).
    pub first_step: f64,
    /// The most evaluations (value and gradient together).
    pub max_evaluations: usize,
}

impl Default for Settings {
    fn default() -> Settings {
        Settings { memory: 10, gtol: 1e-8, xtol: 1e-9, ftol: 1e-12, first_step: 0.1, max_evaluations: 1000 }
    }
}

/// Why [`maximize`] stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stop {
    /// The projected gradient fell to [`Settings::gtol`].
    Gradient,
    /// A step fell to [`Settings::xtol`].
    Step,
    /// An iteration raised the objective by at most [`Settings::ftol`] of it.
    Progress,
    /// No step along the projected gradient raised the objective: its rounding limits the search.
    LineSearch,
    /// The evaluations reached [`Settings::max_evaluations`].
    Evaluations,
}

impl Stop {
    /// Whether the search converged (it did not run out of evaluations).
    pub fn converged(self) -> bool {
        self != Stop::Evaluations
    }

    /// Why the search stopped, in words.
    pub fn describe(self) -> &'static str {
        match self {
            Stop::Gradient => "converged: the projected gradient fell below its tolerance",
            Stop::Step => "converged: the step fell below --xtol × each key's range",
            Stop::Progress => "converged: an iteration no longer raised the objective by more than its rounding",
            Stop::LineSearch => {
                "converged to roundoff: no step along the projected gradient raises the objective (its own numerical noise)"
            }
            Stop::Evaluations => "not converged: stopped at --max-evaluations (raise it, or loosen --xtol)",
        }
    }
}

/// What [`maximize`] found.
#[derive(Clone, Debug)]
pub struct Found {
    /// The best point (the last accepted: the search only ever rises).
    pub x: Vec<f64>,
    /// The objective there.
    pub value: f64,
    /// The gradient there.
    pub gradient: Vec<f64>,
    /// The largest component of the projected gradient there.
    pub projected_gradient: f64,
    /// Every point evaluated, in order, with its value (`None` where the objective refused it).
    pub history: Vec<(Vec<f64>, Option<f64>)>,
    /// Accepted steps.
    pub iterations: usize,
    /// Why it stopped.
    pub stop: Stop,
    /// The inverse of the objective's curvature (`−∇²f`) estimated from the curvature pairs:
    /// L-BFGS's `H`, row by row; exact along the directions the search moved (for a quadratic),
    /// its scaling `γ = s·y/y·y` elsewhere.
    pub inverse_curvature: Vec<Vec<f64>>,
    /// Curvature pairs behind `inverse_curvature` (fewer than the keys: it is a guess in the
    /// directions the search did not move).
    pub pairs: usize,
}

/// The clamp of `x` into `[lo, hi]` key by key.
fn project(x: &[f64], lo: &[f64], hi: &[f64]) -> Vec<f64> {
    x.iter().zip(lo.iter().zip(hi)).map(|(&v, (&l, &h))| v.clamp(l, h)).collect()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn max_abs(a: &[f64]) -> f64 {
    a.iter().fold(0.0, |m, v| m.max(v.abs()))
}

/// `P(x + g) − x`, the projected gradient's components (ascent).
pub fn projected_gradient(x: &[f64], gradient: &[f64], lo: &[f64], hi: &[f64]) -> Vec<f64> {
    x.iter().zip(gradient).zip(lo.iter().zip(hi)).map(|((&x, &g), (&l, &h))| (x + g).clamp(l, h) - x).collect()
}

/// The L-BFGS memory for minimizing `−f`: pairs `(s, y)` with `y` the change of `−∇f`.
struct Memory {
    pairs: std::collections::VecDeque<(Vec<f64>, Vec<f64>)>,
    size: usize,
}

impl Memory {
    /// `H v` by the two-loop recursion, in the coordinates where `free` is true (the others 0).
    fn apply(&self, v: &[f64], free: &[bool]) -> Vec<f64> {
        let mask = |a: &[f64]| -> Vec<f64> { a.iter().zip(free).map(|(&x, &f)| if f { x } else { 0.0 }).collect() };
        let mut q = mask(v);
        let mut alphas = Vec::with_capacity(self.pairs.len());
        for (s, y) in self.pairs.iter().rev() {
            let (s, y) = (mask(s), mask(y));
            let sy = dot(&s, &y);
            if sy <= 0.0 {
                alphas.push(0.0);
                continue;
            }
            let a = dot(&s, &q) / sy;
            q.iter_mut().zip(&y).for_each(|(q, y)| *q -= a * y);
            alphas.push(a);
        }
        let gamma = self
            .pairs
            .back()
            .map(|(s, y)| {
                let (s, y) = (mask(s), mask(y));
                let (sy, yy) = (dot(&s, &y), dot(&y, &y));
                if sy > 0.0 && yy > 0.0 { sy / yy } else { 1.0 }
            })
            .unwrap_or(1.0);
        q.iter_mut().for_each(|q| *q *= gamma);
        for ((s, y), a) in self.pairs.iter().zip(alphas.iter().rev()) {
            let (s, y) = (mask(s), mask(y));
            let sy = dot(&s, &y);
            if sy <= 0.0 {
                continue;
            }
            let b = dot(&y, &q) / sy;
            q.iter_mut().zip(&s).for_each(|(q, s)| *q += (a - b) * s);
        }
        q
    }

    fn push(&mut self, s: Vec<f64>, y: Vec<f64>) {
        if self.size == 0 {
            return;
        }
        if self.pairs.len() == self.size {
            self.pairs.pop_front();
        }
        self.pairs.push_back((s, y));
    }
}

/// Maximizes `f` (which returns the value and the gradient) on the box `[lo, hi]` from `x0`
/// (clamped into the box) by projected L-BFGS (module docs). `f` may return `Ok(None)` for a
/// point it refuses to score (outside a model's validity): the line search treats it as lower
/// than any other and steps back. An error of `f` stops the search and is returned. The
/// starting point must be scored.
pub fn maximize(
    lo: &[f64],
    hi: &[f64],
    x0: &[f64],
    settings: &Settings,
    mut f: impl FnMut(&[f64]) -> Result<Scored>,
) -> Result<Found> {
    let n = x0.len();
    anyhow::ensure!(
        lo.len() == n && hi.len() == n,
        "internal error: {n} keys but {} and {} bounds",
        lo.len(),
        hi.len()
    );
    anyhow::ensure!(lo.iter().zip(hi).all(|(l, h)| l < h), "internal error: a bound with LO ≥ HI");
    let mut history: Vec<(Vec<f64>, Option<f64>)> = Vec::new();
    let mut evaluate = |x: &[f64], history: &mut Vec<(Vec<f64>, Option<f64>)>| -> Result<Scored> {
        let v = f(x)?.filter(|(v, g)| v.is_finite() && g.len() == n && g.iter().all(|g| g.is_finite()));
        history.push((x.to_vec(), v.as_ref().map(|(v, _)| *v)));
        Ok(v)
    };
    let mut x = project(x0, lo, hi);
    let Some((mut value, mut gradient)) = evaluate(&x, &mut history)? else {
        anyhow::bail!("internal error: the search's starting point has no score");
    };
    let mut memory = Memory { pairs: Default::default(), size: settings.memory };
    let mut iterations = 0;
    let stop = loop {
        let pg = projected_gradient(&x, &gradient, lo, hi);
        if max_abs(&pg) <= settings.gtol {
            break Stop::Gradient;
        }
        if history.len() >= settings.max_evaluations {
            break Stop::Evaluations;
        }
        // the binding set: at a bound, the gradient pushing outward
        let free: Vec<bool> =
            (0..n).map(|i| !((x[i] <= lo[i] && gradient[i] < 0.0) || (x[i] >= hi[i] && gradient[i] > 0.0))).collect();
        let mut accepted = None;
        let mut out_of_evaluations = false;
        for quasi_newton in [true, false] {
            if !quasi_newton {
                memory.pairs.clear();
            }
            // ascent direction: H ∇f (H the inverse of −∇²f)
            let mut d = memory.apply(&gradient, &free);
            if memory.pairs.is_empty() {
                let size = max_abs(&d);
                if size > 0.0 {
                    let scale = settings.first_step / size;
                    d.iter_mut().for_each(|d| *d *= scale);
                }
            }
            if dot(&d, &gradient) <= 0.0 {
                continue;
            }
            let mut alpha = 1.0;
            for _ in 0..BACKTRACKS {
                let trial: Vec<f64> =
                    project(&x.iter().zip(&d).map(|(x, d)| x + alpha * d).collect::<Vec<_>>(), lo, hi);
                let s: Vec<f64> = trial.iter().zip(&x).map(|(t, x)| t - x).collect();
                if max_abs(&s) == 0.0 {
                    break;
                }
                let rise = dot(&gradient, &s);
                if rise > 0.0 {
                    if history.len() >= settings.max_evaluations {
                        out_of_evaluations = true;
                        break;
                    }
                    if let Some((v, g)) = evaluate(&trial, &mut history)?
                        && v >= value + ARMIJO * rise
                        && v > value
                    {
                        accepted = Some((trial, s, v, g));
                        break;
                    }
                }
                alpha *= 0.5;
            }
            if accepted.is_some() || out_of_evaluations {
                break;
            }
        }
        let Some((trial, s, v, g)) = accepted else {
            break if out_of_evaluations { Stop::Evaluations } else { Stop::LineSearch };
        };
        iterations += 1;
        // y = change of −∇f; a maximum's curvature makes s·y > 0
        let y: Vec<f64> = g.iter().zip(&gradient).map(|(g1, g0)| g0 - g1).collect();
        let sy = dot(&s, &y);
        if sy > 1e-12 * dot(&s, &s).sqrt() * dot(&y, &y).sqrt() {
            memory.push(s.clone(), y);
        }
        let rise = v - value;
        (x, value, gradient) = (trial, v, g);
        if max_abs(&s) <= settings.xtol {
            break Stop::Step;
        }
        if rise <= settings.ftol * value.abs().max(1.0) {
            break Stop::Progress;
        }
    };
    let projected = max_abs(&projected_gradient(&x, &gradient, lo, hi));
    let all = vec![true; n];
    let inverse_curvature = (0..n)
        .map(|i| {
            let mut e = vec![0.0; n];
            e[i] = 1.0;
            memory.apply(&e, &all)
        })
        .collect();
    let pairs = memory.pairs.len();
    Ok(Found { x, value, gradient, projected_gradient: projected, history, iterations, stop, inverse_curvature, pairs })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A concave quadratic `f = −½ (x − c)ᵀ A (x − c)` with its gradient.
    fn quadratic(a: Vec<Vec<f64>>, c: Vec<f64>) -> impl Fn(&[f64]) -> Result<Scored> {
        move |x: &[f64]| {
            let r: Vec<f64> = x.iter().zip(&c).map(|(x, c)| x - c).collect();
            let ar: Vec<f64> = a.iter().map(|row| dot(row, &r)).collect();
            Ok(Some((-0.5 * dot(&r, &ar), ar.iter().map(|v| -v).collect())))
        }
    }

    /// The optimum inside the box: a coupled quadratic in 4 keys to 1e-7, the projected gradient
    /// to its tolerance, and the estimated inverse curvature is A⁻¹ along the directions moved.
    #[test]
    fn a_bounded_quadratic_with_its_optimum_inside() {
        let a = vec![
            vec![4.0, 1.0, 0.0, 0.0],
            vec![1.0, 3.0, 0.5, 0.0],
            vec![0.0, 0.5, 2.0, 0.2],
            vec![0.0, 0.0, 0.2, 1.0],
        ];
        let c = vec![0.3, -0.2, 0.7, 0.1];
        let (lo, hi) = (vec![-1.0; 4], vec![1.0; 4]);
        let found =
            maximize(&lo, &hi, &[0.9, 0.9, -0.9, -0.9], &Settings::default(), quadratic(a.clone(), c.clone())).unwrap();
        for (x, c) in found.x.iter().zip(&c) {
            assert!((x - c).abs() < 1e-7, "{:?}", found.x);
        }
        assert!(
            found.stop.converged() && found.projected_gradient < 1e-6,
            "{:?} {}",
            found.stop,
            found.projected_gradient
        );
        assert!(found.history.len() < 60, "{} evaluations", found.history.len());
        // H A ≈ I to 1 %: the search moved in all four directions of the quadratic (its line
        // searches are not exact, so the pairs are not exactly conjugate)
        for (i, h) in found.inverse_curvature.iter().enumerate() {
            for (j, col) in (0..4).map(|j| a.iter().map(|r| r[j]).collect::<Vec<_>>()).enumerate() {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((dot(h, &col) - want).abs() < 1e-2, "(HA)[{i}][{j}] = {}", dot(h, &col));
            }
        }
    }

    /// The optimum on a bound: the unconstrained maximum of the quadratic lies outside the box,
    /// the bounded one (found by the KKT conditions written here) on its faces.
    #[test]
    fn a_bounded_quadratic_with_its_optimum_on_a_bound() {
        // f = −(x0 − 2)² − (x1 − 0.3)² − (x0 − x1)²/2 on [−1, 1]²: x0 = 1 on its bound, then
        // ∂f/∂x1 = −2(x1 − 0.3) + (1 − x1) = 0 gives x1 = 1.6/3, and ∂f/∂x0 = 2 − (1 − x1) > 0
        // there pushes x0 out of the box (the KKT conditions of the bounded maximum)
        let f = |x: &[f64]| -> Result<Scored> {
            let v = -(x[0] - 2.0).powi(2) - (x[1] - 0.3).powi(2) - 0.5 * (x[0] - x[1]).powi(2);
            let g0 = -2.0 * (x[0] - 2.0) - (x[0] - x[1]);
            let g1 = -2.0 * (x[1] - 0.3) + (x[0] - x[1]);
            Ok(Some((v, vec![g0, g1])))
        };
        let (lo, hi) = (vec![-1.0; 2], vec![1.0; 2]);
        let found = maximize(&lo, &hi, &[-0.5, -0.5], &Settings::default(), f).unwrap();
        assert_eq!(found.x[0], 1.0, "{:?}", found.x);
        assert!((found.x[1] - 1.6 / 3.0).abs() < 1e-7, "{:?}", found.x);
        // the gradient pushes outward at the bound; the projected gradient vanishes
        assert!(
            found.gradient[0] > 0.5 && found.projected_gradient < 1e-6,
            "{:?} {}",
            found.gradient,
            found.projected_gradient
        );
        assert!(found.stop.converged(), "{:?}", found.stop);
    }

    /// The Rosenbrock function in 10 keys (maximizing its negative), from the classic start
    /// (−1.2, 1, −1.2, 1, …): the optimum at all ones to 1e-5, inside a box that holds it; and
    /// in a box whose upper bound 0.5 cuts it off, the bounded optimum satisfies the KKT
    /// conditions (projected gradient small, the gradient pushing outward at every bound key).
    #[test]
    fn rosenbrock_in_ten_keys() {
        let rosenbrock = |x: &[f64]| -> Result<Scored> {
            let n = x.len();
            let mut v = 0.0;
            let mut g = vec![0.0; n];
            for i in 0..n - 1 {
                let (a, b) = (x[i + 1] - x[i] * x[i], 1.0 - x[i]);
                v += 100.0 * a * a + b * b;
                g[i] += -400.0 * a * x[i] - 2.0 * b;
                g[i + 1] += 200.0 * a;
            }
            Ok(Some((-v, g.iter().map(|g| -g).collect())))
        };
        let x0: Vec<f64> = (0..10).map(|i| if i % 2 == 0 { -1.2 } else { 1.0 }).collect();
        let settings = Settings { max_evaluations: 5000, ..Settings::default() };
        let found = maximize(&[-2.0; 10], &[2.0; 10], &x0, &settings, rosenbrock).unwrap();
        for x in &found.x {
            assert!((x - 1.0).abs() < 1e-5, "{:?} ({:?}, {} evaluations)", found.x, found.stop, found.history.len());
        }
        assert!(found.value > -1e-9 && found.stop.converged(), "{} {:?}", found.value, found.stop);
        let found = maximize(&[-2.0; 10], &[0.5; 10], &x0, &settings, rosenbrock).unwrap();
        assert!(
            found.stop.converged() && found.projected_gradient < 1e-5,
            "{:?} {}",
            found.stop,
            found.projected_gradient
        );
        for (x, g) in found.x.iter().zip(&found.gradient) {
            if *x >= 0.5 {
                assert!(*g >= 0.0, "{:?} {:?}", found.x, found.gradient);
            } else {
                assert!(g.abs() < 1e-5, "{:?} {:?}", found.x, found.gradient);
            }
        }
        // x_0 = 0.5 is a bound point of the solution (every key would reach 1 unbounded)
        assert_eq!(found.x[0], 0.5, "{:?}", found.x);
    }

    /// A refused point (`None`) is stepped back from; the evaluation limit stops the search and
    /// says so; an error of the objective is returned.
    #[test]
    fn refused_points_the_evaluation_limit_and_errors() {
        // the maximum at 0.8 lies beyond the refused region x > 0.6: the search ends near 0.6
        let f = |x: &[f64]| -> Result<Scored> {
            Ok((x[0] <= 0.6).then(|| (-(x[0] - 0.8).powi(2), vec![-2.0 * (x[0] - 0.8)])))
        };
        let found = maximize(&[0.0], &[1.0], &[0.1], &Settings::default(), f).unwrap();
        assert!(found.x[0] <= 0.6 && found.x[0] > 0.59, "{:?} {:?}", found.x, found.stop);
        assert!(found.history.iter().any(|(_, v)| v.is_none()));
        let few = Settings { max_evaluations: 3, ..Settings::default() };
        let slow = |x: &[f64]| -> Result<Scored> { Ok(Some((x[0], vec![1e-3]))) };
        let found = maximize(&[0.0], &[100.0], &[0.0], &few, slow).unwrap();
        assert_eq!(found.stop, Stop::Evaluations);
        assert!(!found.stop.converged() && found.history.len() == 3);
        let bad = |x: &[f64]| -> Result<Scored> {
            if x[0] > 0.05 { anyhow::bail!("bad at {}", x[0]) } else { Ok(Some((x[0], vec![1.0]))) }
        };
        assert!(
            maximize(&[0.0], &[1.0], &[0.0], &Settings::default(), bad).unwrap_err().to_string().contains("bad at")
        );
    }
}
