//! Wind: quadratic normal drag of every cloth triangle in moving air, docs/MATH.md §23.
//!
//! Triangle `(a, b, c)` with `N = (x_b - x_a) × (x_c - x_a)` (area `A = |N|/2`, normal
//! `n = N/|N|`) moving with the mean velocity `v_t` of its vertices in air of velocity
//! `v_air(t)` (the sum of every [`Wind`]'s) feels
//!
//! `f = ½ ρ C_d A (v_rel·n)|v_rel·n| n = k w|w| N/|N|²`, `v_rel = v_air - v_t`, `w = v_rel·N`,
//! `k = ρ C_d / 4`,
//!
//! a third on each vertex. Only the normal component of the relative velocity is resisted (no
//! skin friction). `∂f/∂v` is symmetric negative semi-definite and is what enters the
//! matrix; `∂f/∂x` (the area and the normal turning) is not symmetric and stays out of it
//! (exposed by [`WindForce::jacobians`] and checked against finite differences).
//!
//! With a lift coefficient `C_l` (`lift`, default 0) the triangle also feels the lift
//!
//! `f_L = ½ ρ C_l A (v_rel·n)|v_rel| (n - (n·û) û) = k_l (w|v_rel| N - w² v_rel/|v_rel|)/|N|`,
//! `û = v_rel/|v_rel|`, `k_l = ρ C_l / 4`,
//!
//! perpendicular to `v_rel` (it does no work on the relative motion), in the plane of `n` and
//! `v_rel`, on the side the drag pushes across the flow, of size `½ ρ C_l A |v_rel|² sin α cos α`
//! for a flow at `α` to the triangle's plane: zero edge-on and face-on. Lift is not the
//! gradient of a dissipation potential and its `∂f/∂v` is not symmetric: it is explicit within
//! a step (its Jacobians stay out of the matrix and `Ψ` leaves it out; docs/MATH.md §23).

use super::State;
use super::stencil::{Full, Gather, StencilForce};
use crate::error::{Error, Result};
use crate::math::{Mat3, Vec3, outer};
use crate::validate;

/// Default air density, kg/m³ (air at about 20 °C, sea level).
pub const DEFAULT_DENSITY: f64 = 1.2;
/// Default normal drag coefficient (a flat plate face-on is about 1.2; 1 is the round value).
pub const DEFAULT_DRAG: f64 = 1.0;
/// Default lift coefficient: no lift.
pub const DEFAULT_LIFT: f64 = 0.0;

/// How the air's velocity varies in time.
#[derive(Clone, Debug, PartialEq)]
pub enum AirVelocity {
    /// The same velocity at all times, m/s.
    Constant(Vec3),
    /// `(time s, velocity m/s)` keys with increasing times: piecewise linear between keys, held
    /// before the first and after the last.
    Keyframes(Vec<(f64, Vec3)>),
}

impl AirVelocity {
    /// The velocity at time `t`.
    pub fn at(&self, t: f64) -> Vec3 {
        let keys = match self {
            AirVelocity::Constant(v) => return *v,
            AirVelocity::Keyframes(k) => k,
        };
        let after = keys.partition_point(|&(time, _)| time <= t);
        match (after.checked_sub(1), keys.get(after)) {
            (None, _) => keys[0].1,
            (Some(i), None) => keys[i].1,
            (Some(i), Some(&(t1, v1))) => {
                let (t0, v0) = keys[i];
                v0 + (t - t0) / (t1 - t0) * (v1 - v0)
            }
        }
    }
}

/// The largest speed the air of `winds` reaches at any time, m/s (a bound: the sum of each
/// wind's largest key speed).
pub fn speed_bound(winds: &[Wind]) -> f64 {
    winds
        .iter()
        .map(|w| match &w.velocity {
            AirVelocity::Constant(v) => v.length(),
            AirVelocity::Keyframes(k) => k.iter().fold(0.0, |m: f64, (_, v)| m.max(v.length())),
        })
        .sum()
}

/// One `[[wind]]`: moving air acting on every cloth triangle.
#[derive(Clone, Debug, PartialEq)]
pub struct Wind {
    /// The air's velocity.
    pub velocity: AirVelocity,
    /// Air density, kg/m³ (> 0).
    pub density: f64,
    /// Normal drag coefficient `C_d` (≥ 0).
    pub drag: f64,
    /// Lift coefficient `C_l` (≥ 0; 0: no lift).
    pub lift: f64,
}

impl Wind {
    /// A constant wind with the default density and drag.
    pub fn constant(velocity: Vec3) -> Wind {
        Wind {
            velocity: AirVelocity::Constant(velocity),
            density: DEFAULT_DENSITY,
            drag: DEFAULT_DRAG,
            lift: DEFAULT_LIFT,
        }
    }

    /// Checks the wind; errors name `field.KEY` (`wind[0].keyframes[1].time`).
    pub fn validate(&self, field: &str) -> Result<()> {
        match &self.velocity {
            AirVelocity::Constant(v) => {
                validate::finite3(&format!("{field}.velocity"), *v)?;
            }
            AirVelocity::Keyframes(keys) => {
                if keys.is_empty() {
                    return Err(Error::field(
                        format!("{field}.keyframes"),
                        "is empty: give at least one { time, velocity }",
                    ));
                }
                for (k, &(time, v)) in keys.iter().enumerate() {
                    let at = format!("{field}.keyframes[{k}]");
                    if !time.is_finite() {
                        return Err(Error::field(
                            format!("{at}.time"),
                            format!("must be a finite number, got {time}"),
                        ));
                    }
                    let before = if k > 0 {
                        keys[k - 1].0
                    } else {
                        f64::NEG_INFINITY
                    };
                    if !(time > before) {
                        return Err(Error::field(
                            format!("{at}.time"),
                            format!(
                                "{time} is not after the previous keyframe's {before} (times must increase)"
                            ),
                        ));
                    }
                    validate::finite3(&format!("{at}.velocity"), v)?;
                }
            }
        }
        validate::positive(&format!("{field}.density"), self.density)?;
        validate::nonneg(&format!("{field}.drag"), self.drag)?;
        validate::nonneg(&format!("{field}.lift"), self.lift)?;
        Ok(())
    }
}

/// Checks every wind (`wind[i]`) and that they agree on density, drag and lift: the winds are
/// one air, whose velocity is the sum of theirs.
pub fn validate_winds(winds: &[Wind]) -> Result<()> {
    for (i, w) in winds.iter().enumerate() {
        w.validate(&format!("wind[{i}]"))?;
    }
    let Some(first) = winds.first() else {
        return Ok(());
    };
    for (i, w) in winds.iter().enumerate().skip(1) {
        for (key, mine, theirs) in [
            ("density", w.density, first.density),
            ("drag", w.drag, first.drag),
            ("lift", w.lift, first.lift),
        ] {
            if mine != theirs {
                return Err(Error::field(
                    format!("wind[{i}].{key}"),
                    format!(
                        "{mine} differs from wind[0]'s {theirs}: the winds are one air (their velocities add), so they share density, drag and lift"
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Below this `|N|²` (m⁴) a triangle has no area and no normal: no force.
const MIN_AREA2: f64 = 1e-300;

/// `skew(e) y = e × y`.
pub(crate) fn skew(e: Vec3) -> Mat3 {
    Mat3::from_cols(
        Vec3::new(0.0, e.z, -e.y),
        Vec3::new(-e.z, 0.0, e.x),
        Vec3::new(e.y, -e.x, 0.0),
    )
}

/// `N = (x_b - x_a) × (x_c - x_a)` of triangle `t` and `∂N/∂x_j = skew(e_j)` with
/// `e = [x_c - x_b, x_a - x_c, x_b - x_a]`.
pub(crate) fn area_normal(t: [u32; 3], x: &[Vec3]) -> (Vec3, [Vec3; 3]) {
    let [a, b, c] = t.map(|i| x[i as usize]);
    ((b - a).cross(c - a), [c - b, a - c, b - a])
}

/// The wind force on a set of triangles.
#[derive(Clone, Debug)]
pub struct WindForce {
    /// The triangles (global particle indices).
    pub triangles: Vec<[u32; 3]>,
    /// The winds, whose velocities add (density, drag and lift of the first; all agree).
    pub winds: Vec<Wind>,
    /// Gather lists for the parallel sums.
    pub sums: Gather<Full<3>>,
}

/// One triangle's state: `N`, `|N|²`, `v_rel`, `w = v_rel·N`.
struct Local {
    n: Vec3,
    s2: f64,
    rel: Vec3,
    w: f64,
}

impl WindForce {
    /// The force of `winds` on `triangles`.
    pub fn new(triangles: Vec<[u32; 3]>, winds: Vec<Wind>) -> WindForce {
        WindForce {
            triangles,
            winds,
            sums: Gather::default(),
        }
    }

    /// The air's velocity at `t`: the sum of the winds'.
    pub fn air(&self, t: f64) -> Vec3 {
        self.winds.iter().map(|w| w.velocity.at(t)).sum()
    }

    /// `k = ρ C_d / 4`.
    fn k(&self) -> f64 {
        self.winds
            .first()
            .map_or(0.0, |w| 0.25 * w.density * w.drag)
    }

    /// `k_l = ρ C_l / 4`.
    fn k_lift(&self) -> f64 {
        self.winds
            .first()
            .map_or(0.0, |w| 0.25 * w.density * w.lift)
    }

    /// The lift on triangle `l`, `k_l (w|v_rel| N - w² v_rel/|v_rel|)/|N|` (0 in still air).
    fn lift(&self, l: &Local) -> Vec3 {
        let q = l.rel.length();
        if !(q > 0.0) {
            return Vec3::ZERO;
        }
        (self.k_lift() / l.s2.sqrt()) * (l.w * q * l.n - (l.w * l.w / q) * l.rel)
    }

    /// The exact `(∂f/∂x, ∂f/∂v)` blocks of the lift on triangle `s` (see
    /// [`WindForce::jacobians`]; they stay out of the matrix).
    pub fn lift_jacobians(&self, s: usize, at: &State) -> ([[Mat3; 3]; 3], [[Mat3; 3]; 3]) {
        let zero = [[Mat3::ZERO; 3]; 3];
        let Some(l) = self.local(s, at) else {
            return (zero, zero);
        };
        let (q, kl) = (l.rel.length(), self.k_lift());
        if !(q > 0.0) || kl == 0.0 {
            return (zero, zero);
        }
        let (_, e) = area_normal(self.triangles[s], at.x);
        let f = self.lift(&l);
        let (u, n, w, len) = (l.rel, l.n, l.w, l.s2.sqrt());
        // ∂f/∂N
        let g = (kl / len)
            * (q * outer(n, u) + (q * w) * Mat3::IDENTITY - (2.0 * w / q) * outer(u, u))
            - outer(f, n) / l.s2;
        // ∂f/∂v_rel; v_rel = v_air - (v_a + v_b + v_c)/3
        let uh = u / q;
        let du = (kl / len)
            * (q * outer(n, n) + w * outer(n, uh)
                - 2.0 * w * outer(uh, n)
                - (w * w / q) * (Mat3::IDENTITY - outer(uh, uh)));
        let dx = std::array::from_fn(|_| std::array::from_fn(|j| g * skew(e[j]) / 3.0));
        (dx, [[-du / 9.0; 3]; 3])
    }

    fn local(&self, s: usize, at: &State) -> Option<Local> {
        let t = self.triangles[s];
        let (n, _) = area_normal(t, at.x);
        let s2 = n.length_squared();
        if !(s2 > MIN_AREA2) {
            return None;
        }
        let mean = t.iter().map(|&i| at.v[i as usize]).sum::<Vec3>() / 3.0;
        let rel = self.air(at.t) - mean;
        Some(Local {
            n,
            s2,
            rel,
            w: rel.dot(n),
        })
    }

    /// The exact `(∂f/∂x, ∂f/∂v)` blocks of triangle `s` (drag and lift), `[i][j]` =
    /// `∂f_i/∂(x or v)_j`. Only the drag's `∂f/∂v` ([`WindForce::drag_jacobians`]) enters the
    /// matrix.
    pub fn jacobians(&self, s: usize, at: &State) -> ([[Mat3; 3]; 3], [[Mat3; 3]; 3]) {
        let (dx, dv) = self.drag_jacobians(s, at);
        let (lx, lv) = self.lift_jacobians(s, at);
        let add = |a: [[Mat3; 3]; 3], b: [[Mat3; 3]; 3]| {
            std::array::from_fn(|i| std::array::from_fn(|j| a[i][j] + b[i][j]))
        };
        (add(dx, lx), add(dv, lv))
    }

    /// The exact `(∂f/∂x, ∂f/∂v)` blocks of the drag on triangle `s`.
    pub fn drag_jacobians(&self, s: usize, at: &State) -> ([[Mat3; 3]; 3], [[Mat3; 3]; 3]) {
        let zero = [[Mat3::ZERO; 3]; 3];
        let Some(l) = self.local(s, at) else {
            return (zero, zero);
        };
        let k = self.k();
        let (_, e) = area_normal(self.triangles[s], at.x);
        let nn = outer(l.n, l.n);
        // ∂f_tri/∂N
        let g = (k / l.s2)
            * (2.0 * l.w.abs() * outer(l.n, l.rel)
                + l.w * l.w.abs() * (Mat3::IDENTITY - (2.0 / l.s2) * nn));
        let dx = std::array::from_fn(|_| std::array::from_fn(|j| g * skew(e[j]) / 3.0));
        let dv = [[-(2.0 * k * l.w.abs() / (9.0 * l.s2)) * nn; 3]; 3];
        (dx, dv)
    }
}

impl StencilForce for WindForce {
    type Shape = Full<3>;
    const NAME: &'static str = "wind";
    fn gather(&self) -> &Gather<Full<3>> {
        &self.sums
    }
    fn count(&self) -> usize {
        self.triangles.len()
    }
    fn particles(&self, s: usize) -> [u32; 3] {
        self.triangles[s]
    }
    /// `Ψ = k |w|³ / (3 |N|²)` per triangle: `-∂Ψ/∂v` is the force (at fixed `x` and `t`).
    fn local_dissipation(&self, s: usize, at: &State) -> f64 {
        self.local(s, at)
            .map_or(0.0, |l| self.k() * l.w.abs().powi(3) / (3.0 * l.s2))
    }
    fn local_force(&self, s: usize, at: &State) -> [Vec3; 3] {
        let f = self.local(s, at).map_or(Vec3::ZERO, |l| {
            let drag = (self.k() * l.w * l.w.abs() / l.s2) * l.n;
            if self.k_lift() == 0.0 {
                drag
            } else {
                drag + self.lift(&l)
            }
        });
        [f / 3.0; 3]
    }
    fn has_jacobian(&self, _a: f64, b: f64) -> bool {
        b != 0.0
    }
    /// `b ∂f/∂v` of the drag (the position Jacobian and the lift's are not symmetric and stay
    /// out of the matrix).
    fn local_jacobian(&self, s: usize, at: &State, _a: f64, b: f64) -> [[Mat3; 3]; 3] {
        self.drag_jacobians(s, at).1.map(|row| row.map(|m| b * m))
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::*;
    use super::super::{Force, Linearization};
    use super::*;
    use proptest::prelude::*;

    /// Two triangles sharing an edge (and one particle twice in neither), random positions and
    /// velocities, a wind of two parts (one keyframed) with random density, drag and lift (the
    /// air at least 0.2 m/s relative to each triangle: lift turns with its direction).
    fn config() -> impl Strategy<Value = (Vec<Vec3>, Vec<Vec3>, WindForce)> {
        (
            prop::collection::vec(arb_vec3(1.0), 4),
            prop::collection::vec(arb_vec3(3.0), 4),
            arb_vec3(3.0),
            arb_vec3(3.0),
            (0.5..2.0f64, 0.1..2.0f64, 0.0..2.0f64),
        )
            .prop_filter_map("non-degenerate", |(x, v, a, b, (rho, cd, cl))| {
                let tris = vec![[0, 1, 2], [2, 1, 3]];
                if tris.iter().any(|&t| area_normal(t, &x).0.length() < 0.05) {
                    return None;
                }
                let mut one = Wind::constant(a);
                (one.density, one.drag, one.lift) = (rho, cd, cl);
                let two = Wind {
                    velocity: AirVelocity::Keyframes(vec![(0.0, Vec3::ZERO), (1.0, b)]),
                    ..one.clone()
                };
                let f = WindForce::new(tris, vec![one, two]);
                let slow = |t: &[u32; 3]| {
                    let mean = t.iter().map(|&i| v[i as usize]).sum::<Vec3>() / 3.0;
                    (f.air(T) - mean).length() < 0.2
                };
                if f.triangles.iter().any(slow) {
                    return None;
                }
                Some((x, v, f))
            })
    }

    /// The Jacobians `jac` gives of every triangle, assembled densely.
    fn exact(
        f: &WindForce,
        x: &[Vec3],
        v: &[Vec3],
        jac: Jacobians,
    ) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
        let at = at(x, v);
        let n = x.len();
        let (dx, dv): (Vec<_>, Vec<_>) = (0..f.count()).map(|s| jac(f, s, &at)).unzip();
        let dense =
            |blocks: Vec<[[Mat3; 3]; 3]>| dense_blocks(n, f.triangles.iter().copied().zip(blocks));
        (dense(dx), dense(dv))
    }

    /// A triangle's exact `(∂f/∂x, ∂f/∂v)` blocks: all, the drag's or the lift's.
    type Jacobians = fn(&WindForce, usize, &State) -> ([[Mat3; 3]; 3], [[Mat3; 3]; 3]);

    proptest! {
        #[test]
        fn wind_jacobians_match_central_differences((x, v, f) in config()) {
            let (dx, dv) = exact(&f, &x, &v, WindForce::jacobians);
            let fdx = fd_jacobian(&f, &x, &v, false);
            let fdv = fd_jacobian(&f, &x, &v, true);
            prop_assert!(rel_diff(&dx, &fdx) < 1e-6, "∂f/∂x: {}", rel_diff(&dx, &fdx));
            prop_assert!(rel_diff(&dv, &fdv) < 1e-6, "∂f/∂v: {}", rel_diff(&dv, &fdv));
            // the lift's alone: the difference of the force with and without it
            let mut plain = f.clone();
            plain.winds.iter_mut().for_each(|w| w.lift = 0.0);
            let (lx, lv) = exact(&f, &x, &v, WindForce::lift_jacobians);
            let minus = |a: Vec<Vec<f64>>, b: Vec<Vec<f64>>| -> Vec<Vec<f64>> {
                a.iter().zip(&b).map(|(r, s)| r.iter().zip(s).map(|(p, q)| p - q).collect()).collect()
            };
            let flx = minus(fdx, fd_jacobian(&plain, &x, &v, false));
            let flv = minus(fdv, fd_jacobian(&plain, &x, &v, true));
            let scale = 1.0 + f.winds[0].lift;
            prop_assert!(rel_diff(&lx, &flx) < 1e-6 * scale, "lift ∂f/∂x: {}", rel_diff(&lx, &flx));
            prop_assert!(rel_diff(&lv, &flv) < 1e-6 * scale, "lift ∂f/∂v: {}", rel_diff(&lv, &flv));
            // the matrix holds the drag's b ∂f/∂v only, symmetric, negative semi-definite
            let dv = exact(&f, &x, &v, WindForce::drag_jacobians).1;
            let m = assembled(&f, &x, &v, 0.7, 1.3);
            let scaled: Vec<Vec<f64>> = dv.iter().map(|r| r.iter().map(|e| 1.3 * e).collect()).collect();
            prop_assert!(rel_diff(&m, &scaled) < 1e-12);
            for r in 0..12 {
                for c in 0..12 {
                    prop_assert!((m[r][c] - m[c][r]).abs() <= 1e-12 * (1.0 + m[r][c].abs()));
                }
            }
            prop_assert!(check_product(&f, &x, &v, 0.7, 1.3, &v) < 1e-12);
            let lin = Linearization { t: T, x: &x, v: &v, matrix: (0.7, 1.3), product: (1.3, 0.7), w: &x };
            prop_assert!(linearization_is_bitwise_separate(&f, &lin, &v));
            let mut dvw = vec![Vec3::ZERO; 4];
            f.add_jacobian_product(&at(&x, &v), 0.0, 1.0, &x, &mut dvw);
            let q: f64 = x.iter().zip(&dvw).map(|(a, b)| a.dot(*b)).sum();
            prop_assert!(q <= 1e-9, "wᵀDw = {q}");
        }

        /// `-∂Ψ/∂v` is the drag (lift has no dissipation potential).
        #[test]
        fn wind_force_is_minus_the_velocity_gradient_of_its_dissipation((x, v, mut f) in config()) {
            f.winds.iter_mut().for_each(|w| w.lift = 0.0);
            let mut got = vec![Vec3::ZERO; 4];
            f.add_force(&at(&x, &v), &mut got);
            let mut vp = v.clone();
            for i in 0..4 {
                for d in 0..3 {
                    let e = 1e-6;
                    vp[i][d] = v[i][d] + e;
                    let p = f.dissipation(&at(&x, &vp));
                    vp[i][d] = v[i][d] - e;
                    let m = f.dissipation(&at(&x, &vp));
                    vp[i][d] = v[i][d];
                    let scale = 1.0 + got[i].length();
                    prop_assert!((got[i][d] + (p - m) / (2.0 * e)).abs() < 1e-6 * scale);
                }
            }
        }
    }

    proptest! {
        /// Lift is perpendicular to the relative velocity (no work on the relative motion), in
        /// the plane of the normal and the relative velocity, of size `½ ρ C_l A |v_rel|² sin α
        /// cos α` at the angle `α` between the flow and the triangle's plane, and across the
        /// flow on the side the drag pushes.
        #[test]
        fn wind_lift_is_perpendicular_to_the_flow_with_its_size_and_side((x, v, f) in config()) {
            let at = at(&x, &v);
            let (rho, cl) = (f.winds[0].density, f.winds[0].lift);
            for s in 0..f.count() {
                let l = f.local(s, &at).unwrap();
                let lift = f.lift(&l);
                let (q, len) = (l.rel.length(), l.s2.sqrt());
                let sin = (l.w / (q * len)).abs().min(1.0);
                let want = 0.5 * rho * cl * (0.5 * len) * q * q * sin * (1.0 - sin * sin).sqrt();
                let tol = 1e-12 * (1.0 + rho * cl * len * q * q);
                prop_assert!((lift.length() - want).abs() <= tol, "{} vs {want}", lift.length());
                prop_assert!(lift.dot(l.rel).abs() <= tol * q);
                prop_assert!(lift.dot(l.n.cross(l.rel)).abs() <= tol * q * len);
                let drag = l.w * l.w.abs() / l.s2 * l.n;
                let across = drag - drag.dot(l.rel) / (q * q) * l.rel;
                prop_assert!(lift.dot(across) >= -tol * across.length());
            }
            // the triangles' lift does no work on the relative motion: with the cloth moving
            // rigidly at v_t, Σ f·v_rel = 0
            let still: Vec<Vec3> = vec![v[0]; 4];
            let mut got = vec![Vec3::ZERO; 4];
            let mut only = f.clone();
            only.winds.iter_mut().for_each(|w| w.drag = 0.0);
            only.add_force(&super::super::testing::at(&x, &still), &mut got);
            let rel = f.air(T) - v[0];
            let power: f64 = got.iter().map(|g| g.dot(rel)).sum();
            prop_assert!(power.abs() <= 1e-12 * (1.0 + rho * cl * rel.length_squared() * rel.length()));
        }
    }

    #[test]
    fn lift_is_zero_edge_on_and_face_on_and_half_of_its_size_at_45_degrees() {
        // area ½ in the x–y plane (N = z), at rest in air of speed 3 m/s
        let x = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let v = [Vec3::ZERO; 3];
        let (u, cl) = (3.0, 0.8);
        let total = |air: Vec3| {
            let mut wind = Wind::constant(air);
            (wind.drag, wind.lift) = (0.0, cl);
            let f = WindForce::new(vec![[0, 1, 2]], vec![wind]);
            let mut got = vec![Vec3::ZERO; 3];
            f.add_force(&at(&x, &v), &mut got);
            got.iter().sum::<Vec3>()
        };
        // along the cloth (edge-on) and along its normal (face-on): none
        assert_eq!(total(Vec3::new(u, 0.0, 0.0)), Vec3::ZERO);
        assert_eq!(total(Vec3::new(0.6 * u, -0.8 * u, 0.0)), Vec3::ZERO);
        assert!(total(Vec3::new(0.0, 0.0, u)).length() < 1e-14);
        assert!(total(Vec3::new(0.0, 0.0, -u)).length() < 1e-14);
        // at 45°: ½ ρ C_l A u² sin 45° cos 45° across the flow, toward +z (where the drag
        // pushes), in the x–z plane
        let c = 0.5f64.sqrt();
        let size = 0.5 * DEFAULT_DENSITY * cl * 0.5 * u * u * 0.5;
        let want = size * Vec3::new(-c, 0.0, c);
        let got = total(Vec3::new(c * u, 0.0, c * u));
        assert!((got - want).length() < 1e-14, "{got} vs {want}");
        // the flow from below: the mirror image, lift toward -z
        let got = total(Vec3::new(c * u, 0.0, -c * u));
        assert!(
            (got - size * Vec3::new(-c, 0.0, -c)).length() < 1e-14,
            "{got}"
        );
    }

    #[test]
    fn a_face_on_triangle_feels_half_rho_cd_a_v_squared_against_its_motion() {
        // area ½ in the x–y plane, moving at 2 m/s along +z in still air
        let x = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let v = [Vec3::new(0.0, 0.0, 2.0); 3];
        let f = WindForce::new(vec![[0, 1, 2]], vec![Wind::constant(Vec3::ZERO)]);
        let mut got = vec![Vec3::ZERO; 3];
        f.add_force(&at(&x, &v), &mut got);
        let total: Vec3 = got.iter().sum();
        let want = -0.5 * DEFAULT_DENSITY * DEFAULT_DRAG * 0.5 * 4.0;
        assert!(
            (total - Vec3::new(0.0, 0.0, want)).length() < 1e-12,
            "{total}"
        );
        // edge-on: no force; reversed winding: the same force
        let side = [Vec3::new(2.0, 0.0, 0.0); 3];
        let mut got = vec![Vec3::ZERO; 3];
        f.add_force(&at(&x, &side), &mut got);
        assert!(got.iter().all(|g| g.length() < 1e-15));
        let flipped = WindForce::new(vec![[0, 2, 1]], f.winds.clone());
        let mut again = vec![Vec3::ZERO; 3];
        flipped.add_force(&at(&x, &v), &mut again);
        assert!((again.iter().sum::<Vec3>() - total).length() < 1e-12);
    }

    #[test]
    fn keyframed_air_is_piecewise_linear_and_held_outside() {
        let air = AirVelocity::Keyframes(vec![
            (1.0, Vec3::X),
            (3.0, Vec3::new(3.0, 2.0, 0.0)),
            (4.0, Vec3::ZERO),
        ]);
        assert_eq!(air.at(-5.0), Vec3::X);
        assert_eq!(air.at(1.0), Vec3::X);
        assert_eq!(air.at(2.0), Vec3::new(2.0, 1.0, 0.0));
        assert_eq!(air.at(3.5), Vec3::new(1.5, 1.0, 0.0));
        assert_eq!(air.at(9.0), Vec3::ZERO);
        let f = WindForce::new(
            vec![],
            vec![
                Wind::constant(Vec3::Y),
                Wind {
                    velocity: air,
                    ..Wind::constant(Vec3::ZERO)
                },
            ],
        );
        assert_eq!(f.air(2.0), Vec3::new(2.0, 2.0, 0.0));
    }

    #[test]
    fn bad_winds_name_the_field() {
        let mut w = Wind::constant(Vec3::ZERO);
        w.density = -1.0;
        let e = validate_winds(&[Wind::constant(Vec3::X), w])
            .unwrap_err()
            .to_string();
        assert_eq!(e, "wind[1].density: must be a finite number > 0, got -1");
        let mut w = Wind::constant(Vec3::ZERO);
        w.drag = 2.0;
        let e = validate_winds(&[Wind::constant(Vec3::X), w])
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("wind[1].drag: 2 differs from wind[0]'s 1"),
            "{e}"
        );
        let mut w = Wind::constant(Vec3::ZERO);
        w.lift = f64::NAN;
        let e = validate_winds(&[w]).unwrap_err().to_string();
        assert!(
            e.starts_with("wind[0].lift: must be a finite number ≥ 0"),
            "{e}"
        );
        let mut w = Wind::constant(Vec3::ZERO);
        w.lift = 0.5;
        let e = validate_winds(&[Wind::constant(Vec3::X), w])
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("wind[1].lift: 0.5 differs from wind[0]'s 0"),
            "{e}"
        );
        let w = Wind {
            velocity: AirVelocity::Keyframes(vec![(0.0, Vec3::X), (0.0, Vec3::Y)]),
            ..Wind::constant(Vec3::ZERO)
        };
        let e = validate_winds(&[w]).unwrap_err().to_string();
        assert!(
            e.starts_with("wind[0].keyframes[1].time: 0 is not after"),
            "{e}"
        );
    }
}
