//! Hinge bending (discrete shells), docs/MATH.md §21.
//!
//! Every interior edge of the triangle mesh is a hinge, a stencil `[x0, x1, x2, x3]`: the edge
//! `x0 x1` and the opposite vertices `x2`, `x3` of its two triangles. With `e = x1 - x0`,
//! `n1 = e × (x2 - x0)` and `n2 = (x3 - x0) × e` (parallel when the hinge is flat, whatever the
//! triangles' winding), the dihedral angle is
//! `θ = atan2((n1 × n2)·ê, n1·n2)` in `(-π, π]`: 0 when flat, positive when the wings fold
//! away from `n1` (a ridge seen from the side `n1` points to). The energy is
//! `E = k (θ - θ̄)²` with `θ - θ̄` taken in `[-π, π)` and, for a bending rigidity `B`,
//! `k = ½ B |ē|² / (Ā1 + Ā2)` from the rest edge and triangle areas: then a sheet bent onto a
//! cylinder of radius `R` has energy `½ B / R²` per unit area (the tests check it).
//!
//! The force is `-∇E` from the closed-form gradient of `θ`; the matrix is `-H⁺`, the exact
//! Hessian of `E` projected to positive semi-definite; damping is `f = -α H⁺ v`.
//!
//! A hinge whose triangles have (nearly) no area, or whose edge has no length, has no angle:
//! it exerts nothing (energy, force and matrix 0) until it opens again; one degenerate at
//! rest is inactive for good (`k = 0`).

use super::stencil::{Full, Gather, Local, StencilForce};
use super::{Linearization, State};
use crate::linalg::eigen::project_psd;
use crate::math::{Mat3, Vec3, outer};
use std::collections::HashMap;
use std::collections::hash_map::Entry;
use std::f64::consts::PI;

/// `c` in the hinge weight `k = c B |ē|² / (Ā1 + Ā2)`: the value for which a triangulated
/// sheet bent onto a cylinder has the continuum energy `½ B κ²` per unit area (docs/MATH.md
/// §21; the usual `3/2`, from spreading `½ θ |ē|` of mean curvature over a third of the two
/// triangles, is the calibration on a sphere and is 3 times too stiff on a cylinder).
pub const CYLINDER_WEIGHT: f64 = 0.5;

/// A triangle whose height over the hinge edge is below this fraction of the edge's length
/// counts as degenerate (a sliver of aspect ratio 10⁹).
const MIN_ASPECT: f64 = 1e-9;

/// Hinge bending on a set of stencils `[x0, x1, x2, x3]`.
#[derive(Clone, Debug)]
pub struct Hinges {
    /// The stencils: edge `x0 x1`, opposite vertices `x2` and `x3`.
    pub stencils: Vec<[u32; 4]>,
    /// `k` of each hinge, J (`E = k (θ - θ̄)²`); 0 for a hinge degenerate at rest.
    pub stiffness: Vec<f64>,
    /// Rest angle `θ̄` of each hinge, rad.
    pub rest_angle: Vec<f64>,
    /// Stiffness-proportional damping `α`, s: `f = -α H⁺ v`.
    pub damping: f64,
    /// Gather lists for the parallel sums (build with `Gather::default()`).
    pub sums: Gather<Full<4>>,
}

/// The 12 × 12 matrix of one stencil, row and column `3 a + r` for particle `a`, axis `r`.
type Matrix12 = [[f64; 12]; 12];

/// The dihedral angle of a hinge and what its derivatives need.
#[derive(Clone, Copy, Debug)]
struct Geometry {
    /// `θ`.
    theta: f64,
    /// `∂θ/∂x_i`.
    grad: [Vec3; 4],
    /// `ê`.
    dir: Vec3,
    /// The edge-normal parts `r_k / |e|` of `x2 - x0` and `x3 - x0`.
    rho: [Vec3; 2],
    /// `v_k = n_k / |n_k|²`.
    v: [Vec3; 2],
    /// `∂v_k/∂n_k = (I - 2 N_k N_kᵀ) / |n_k|²`.
    m: [Mat3; 2],
    /// `∂n_k/∂x_i` (`n1` does not depend on `x3`, nor `n2` on `x2`).
    dn: [[Mat3; 4]; 2],
    /// `s[i][k]`: `∂θ/∂x_i = Σ_k s[i][k] v_k`.
    s: [[f64; 2]; 4],
}

/// The cross-product matrix: `skew(w) u = w × u`.
#[inline]
fn skew(w: Vec3) -> Mat3 {
    Mat3::from_cols(
        Vec3::new(0.0, w.z, -w.y),
        Vec3::new(-w.z, 0.0, w.x),
        Vec3::new(w.y, -w.x, 0.0),
    )
}

/// `θ` and its derivatives at `x`, or `None` for a degenerate hinge (see the module docs).
#[inline]
fn geometry(x: [Vec3; 4]) -> Option<Geometry> {
    let [x0, x1, x2, x3] = x;
    let (e, a, b) = (x1 - x0, x2 - x0, x3 - x0);
    let (n1, n2) = (e.cross(a), b.cross(e));
    let l2 = e.length_squared();
    let (q1, q2) = (n1.length_squared(), n2.length_squared());
    // |n_k| = h_k |e|, so h_k > MIN_ASPECT |e| ⇔ |n_k|² > (MIN_ASPECT |e|²)²; the floor keeps
    // 1/|n_k|² finite, and NaN fails every comparison.
    let min = (MIN_ASPECT * l2).powi(2).max(f64::MIN_POSITIVE);
    if !(l2 > 0.0 && q1 > min && q2 > min && l2.is_finite() && q1.is_finite() && q2.is_finite()) {
        return None;
    }
    let l = l2.sqrt();
    let dir = e / l;
    let theta = n1.cross(n2).dot(dir).atan2(n1.dot(n2));
    let v = [n1 / q1, n2 / q2];
    let (p1, p2) = (a.dot(dir), b.dot(dir));
    let s = [[l - p1, l - p2], [p1, p2], [-l, 0.0], [0.0, -l]];
    let grad = s.map(|[s1, s2]| s1 * v[0] + s2 * v[1]);
    let m = [
        (Mat3::IDENTITY - 2.0 * outer(n1, n1) / q1) / q1,
        (Mat3::IDENTITY - 2.0 * outer(n2, n2) / q2) / q2,
    ];
    let dn = [
        [skew(x2 - x1), -skew(a), skew(e), Mat3::ZERO],
        [skew(x1 - x3), skew(b), Mat3::ZERO, -skew(e)],
    ];
    Some(Geometry {
        theta,
        grad,
        dir,
        rho: [(a - p1 * dir) / l, (b - p2 * dir) / l],
        v,
        m,
        dn,
        s,
    })
}

impl Geometry {
    /// `∂s[i][k]/∂x_j`.
    #[inline]
    fn ds(&self, i: usize, k: usize, j: usize) -> Vec3 {
        // ∂|e|/∂x_j and ∂p_k/∂x_j (p_k = (x_{k+2} - x0)·ê)
        let dl = match j {
            0 => -self.dir,
            1 => self.dir,
            _ => Vec3::ZERO,
        };
        let dp = match j {
            0 => -self.dir - self.rho[k],
            1 => self.rho[k],
            _ if j == k + 2 => self.dir,
            _ => Vec3::ZERO,
        };
        match (i, k) {
            (0, _) => dl - dp,
            (1, _) => dp,
            (2, 0) | (3, 1) => -dl,
            _ => Vec3::ZERO,
        }
    }

    /// Block `∂²θ/∂x_i∂x_j` (row `i`, column `j`):
    /// `Σ_k v_k ⊗ ∂s[i][k]/∂x_j + s[i][k] (∂v_k/∂n_k)(∂n_k/∂x_j)`.
    #[inline]
    fn hessian_block(&self, i: usize, j: usize) -> Mat3 {
        let mut h = Mat3::ZERO;
        for k in 0..2 {
            h += outer(self.v[k], self.ds(i, k, j));
            if self.s[i][k] != 0.0 {
                h += self.s[i][k] * (self.m[k] * self.dn[k][j]);
            }
        }
        h
    }
}

/// `θ - θ̄` in `[-π, π)` (both angles in `[-π, π]`).
#[inline]
fn wrapped(theta: f64, rest: f64) -> f64 {
    let d = theta - rest;
    if d >= PI {
        d - 2.0 * PI
    } else if d < -PI {
        d + 2.0 * PI
    } else {
        d
    }
}

/// The dihedral angle of a hinge `[x0, x1, x2, x3]` in `(-π, π]` (see the module docs), or
/// `None` when a triangle has (nearly) no area or the edge no length.
pub fn dihedral_angle(x: [Vec3; 4]) -> Option<f64> {
    geometry(x).map(|g| g.theta)
}

/// `B_e` of a hinge whose rest edge vector is `edge` in the material frame (warp, weft):
/// `B_warp c² + B_weft s²` with `(c, s)` the unit direction across the edge (a hinge across the
/// warp, an edge along the weft, takes `B_warp`). An edge of no length gets the mean.
pub fn rigidity_across(edge: [f64; 2], rigidity: [f64; 2]) -> f64 {
    let l2 = edge[0] * edge[0] + edge[1] * edge[1];
    if !(l2 > 0.0) {
        return 0.5 * (rigidity[0] + rigidity[1]);
    }
    // the direction across the edge is (-e_y, e_x) / |e|
    (rigidity[0] * edge[1] * edge[1] + rigidity[1] * edge[0] * edge[0]) / l2
}

/// Interior edges of a triangle list as hinge stencils `[x0, x1, x2, x3]` with the indices of
/// their two triangles: `x0 → x1` runs as in the first triangle (the one earlier in the list),
/// `x2` is its third vertex and `x3` the second triangle's. Left out: edges of one triangle
/// (the boundary), edges of more than two (non-manifold: no pair of them is more natural than
/// another, so such an edge does not bend), edges whose two triangles have the same third
/// vertex (the same triangle twice), and triangles with a repeated vertex (no area). In order
/// of each edge's first appearance, walking the triangles and each one's edges `(a, b)`,
/// `(b, c)`, `(c, a)`.
pub fn interior_edges(triangles: &[[u32; 3]]) -> Vec<([u32; 4], [usize; 2])> {
    let mut index: HashMap<(u32, u32), usize> = HashMap::with_capacity(2 * triangles.len());
    // stencil, triangles, number of triangles on the edge
    let mut edges: Vec<([u32; 4], [usize; 2], u32)> = Vec::with_capacity(2 * triangles.len());
    for (t, &[a, b, c]) in triangles.iter().enumerate() {
        if a == b || b == c || c == a {
            continue;
        }
        for (p, q, r) in [(a, b, c), (b, c, a), (c, a, b)] {
            match index.entry((p.min(q), p.max(q))) {
                Entry::Vacant(slot) => {
                    slot.insert(edges.len());
                    edges.push(([p, q, r, r], [t, t], 1));
                }
                Entry::Occupied(slot) => {
                    let edge = &mut edges[*slot.get()];
                    edge.2 += 1;
                    if edge.2 == 2 {
                        edge.0[3] = r;
                        edge.1[1] = t;
                    }
                }
            }
        }
    }
    edges
        .into_iter()
        .filter(|(s, _, count)| *count == 2 && s[2] != s[3])
        .map(|(s, t, _)| (s, t))
        .collect()
}

impl Hinges {
    /// Hinges on `stencils` with rest angles from `rest` (rest positions of all particles,
    /// global indexing as the stencils), `rigidity[h]` the `B_e` of hinge `h` (N·m) and
    /// stiffness-proportional `damping` (s).
    ///
    /// # Panics
    /// When `rigidity` and `stencils` differ in length or a stencil indexes outside `rest`.
    pub fn new(rest: &[Vec3], stencils: Vec<[u32; 4]>, rigidity: Vec<f64>, damping: f64) -> Hinges {
        assert_eq!(stencils.len(), rigidity.len(), "one rigidity per hinge");
        let (stiffness, rest_angle) = stencils
            .iter()
            .zip(&rigidity)
            .map(|(st, &b)| {
                let x = st.map(|i| rest[i as usize]);
                match geometry(x) {
                    Some(g) => {
                        let e = x[1] - x[0];
                        let areas =
                            0.5 * (e.cross(x[2] - x[0]).length() + e.cross(x[3] - x[0]).length());
                        (CYLINDER_WEIGHT * b * e.length_squared() / areas, g.theta)
                    }
                    None => (0.0, 0.0),
                }
            })
            .unzip();
        Hinges {
            stencils,
            stiffness,
            rest_angle,
            damping,
            sums: Gather::default(),
        }
    }

    /// Geometry and `θ - θ̄` of hinge `s` at `x`, or `None` when it exerts nothing.
    #[inline]
    fn eval(&self, s: usize, x: &[Vec3]) -> Option<(Geometry, f64)> {
        if self.stiffness[s] == 0.0 {
            return None;
        }
        let g = geometry(self.stencils[s].map(|i| x[i as usize]))?;
        let d = wrapped(g.theta, self.rest_angle[s]);
        Some((g, d))
    }

    /// The exact Hessian `2k (∇θ ∇θᵀ + (θ - θ̄) ∇²θ)` of hinge `s` (upper blocks computed, the
    /// lower mirrored, so it is exactly symmetric).
    fn hessian(&self, s: usize, g: &Geometry, d: f64) -> Matrix12 {
        let k2 = 2.0 * self.stiffness[s];
        let mut h = [[0.0; 12]; 12];
        for i in 0..4 {
            for j in i..4 {
                let mut blk = outer(g.grad[i], g.grad[j]) + d * g.hessian_block(i, j);
                if i == j {
                    blk = 0.5 * (blk + blk.transpose());
                }
                for c in 0..3 {
                    for r in 0..3 {
                        let value = k2 * blk.col(c)[r];
                        h[3 * i + r][3 * j + c] = value;
                        h[3 * j + c][3 * i + r] = value;
                    }
                }
            }
        }
        h
    }

    /// `H⁺` of hinge `s`: the exact Hessian projected to positive semi-definite.
    #[inline]
    fn projected(&self, s: usize, g: &Geometry, d: f64) -> Matrix12 {
        let mut h = self.hessian(s, g, d);
        project_psd::<12>(&mut h);
        h
    }

    /// `H⁺ w` on the particles of stencil `s`.
    #[inline]
    fn times(&self, s: usize, h: &Matrix12, w: &[Vec3]) -> [Vec3; 4] {
        let mut wl = [0.0; 12];
        for (a, &p) in self.stencils[s].iter().enumerate() {
            wl[3 * a..3 * a + 3].copy_from_slice(&w[p as usize].to_array());
        }
        std::array::from_fn(|a| {
            let row = |r: usize| -> f64 { h[3 * a + r].iter().zip(&wl).map(|(m, q)| m * q).sum() };
            Vec3::new(row(0), row(1), row(2))
        })
    }

    /// The force `-2k (θ - θ̄) ∇θ - α H⁺ v` (the damping part when `h` is given).
    #[inline]
    fn force(&self, s: usize, g: &Geometry, d: f64, h: Option<&Matrix12>, v: &[Vec3]) -> [Vec3; 4] {
        let c = -2.0 * self.stiffness[s] * d;
        let mut f = g.grad.map(|gi| c * gi);
        if let Some(h) = h {
            let hv = self.times(s, h, v);
            for (fa, hva) in f.iter_mut().zip(hv) {
                *fa -= self.damping * hva;
            }
        }
        f
    }

    /// `H⁺` when the force needs it (damping on).
    #[inline]
    fn damping_matrix(&self, s: usize, g: &Geometry, d: f64) -> Option<Matrix12> {
        (self.damping != 0.0).then(|| self.projected(s, g, d))
    }
}

/// The blocks of `c H`.
#[inline]
fn blocks(h: &Matrix12, c: f64) -> [[Mat3; 4]; 4] {
    std::array::from_fn(|a| {
        std::array::from_fn(|b| {
            let col = |k: usize| {
                Vec3::new(
                    h[3 * a][3 * b + k],
                    h[3 * a + 1][3 * b + k],
                    h[3 * a + 2][3 * b + k],
                )
            };
            c * Mat3::from_cols(col(0), col(1), col(2))
        })
    })
}

/// Each particle and block takes the stencils' terms one by one ([`super::stencil::Accumulate::Each`]).
impl StencilForce for Hinges {
    type Shape = Full<4>;
    const NAME: &'static str = "hinge bending";
    fn gather(&self) -> &Gather<Full<4>> {
        &self.sums
    }
    fn count(&self) -> usize {
        self.stencils.len()
    }
    fn particles(&self, s: usize) -> [u32; 4] {
        self.stencils[s]
    }
    fn local_energy(&self, s: usize, _t: f64, x: &[Vec3]) -> f64 {
        self.eval(s, x)
            .map_or(0.0, |(_, d)| self.stiffness[s] * d * d)
    }
    /// `½ α vᵀ H⁺ v` on the stencil.
    fn local_dissipation(&self, s: usize, at: &State) -> f64 {
        match self.eval(s, at.x) {
            Some((g, d)) if self.damping != 0.0 => {
                let h = self.projected(s, &g, d);
                let hv = self.times(s, &h, at.v);
                let v = self.stencils[s].map(|p| at.v[p as usize]);
                0.5 * self.damping * v.iter().zip(hv).map(|(a, b)| a.dot(b)).sum::<f64>()
            }
            _ => 0.0,
        }
    }
    fn local_force(&self, s: usize, at: &State) -> [Vec3; 4] {
        match self.eval(s, at.x) {
            Some((g, d)) => {
                let h = self.damping_matrix(s, &g, d);
                self.force(s, &g, d, h.as_ref(), at.v)
            }
            None => [Vec3::ZERO; 4],
        }
    }
    /// `a ∂f/∂x + b ∂f/∂v = -(a + b α) H⁺`.
    fn has_jacobian(&self, a: f64, b: f64) -> bool {
        a + b * self.damping != 0.0
    }
    fn local_jacobian(&self, s: usize, at: &State, a: f64, b: f64) -> [[Mat3; 4]; 4] {
        match self.eval(s, at.x) {
            Some((g, d)) => blocks(&self.projected(s, &g, d), -(a + b * self.damping)),
            None => [[Mat3::ZERO; 4]; 4],
        }
    }
    fn local_product(&self, s: usize, at: &State, a: f64, b: f64, w: &[Vec3]) -> [Vec3; 4] {
        match self.eval(s, at.x) {
            Some((g, d)) => {
                let c = -(a + b * self.damping);
                self.times(s, &self.projected(s, &g, d), w).map(|y| c * y)
            }
            None => [Vec3::ZERO; 4],
        }
    }
    /// One geometry and one projection per stencil for the force, the product and the matrix.
    fn local(&self, s: usize, at: &Linearization, product: bool, matrix: bool) -> Local<Full<4>> {
        let zero = Local {
            force: [Vec3::ZERO; 4],
            product: [Vec3::ZERO; 4],
            matrix: [[Mat3::ZERO; 4]; 4],
        };
        let Some((g, d)) = self.eval(s, at.x) else {
            return zero;
        };
        let h = if product || matrix || self.damping != 0.0 {
            Some(self.projected(s, &g, d))
        } else {
            None
        };
        let force_h = if self.damping != 0.0 {
            h.as_ref()
        } else {
            None
        };
        let force = self.force(s, &g, d, force_h, at.v);
        let (h, (am, bm), (ap, bp)) = (h.unwrap_or([[0.0; 12]; 12]), at.matrix, at.product);
        Local {
            force,
            product: if product {
                let c = -(ap + bp * self.damping);
                self.times(s, &h, at.w).map(|y| c * y)
            } else {
                [Vec3::ZERO; 4]
            },
            matrix: if matrix {
                blocks(&h, -(am + bm * self.damping))
            } else {
                [[Mat3::ZERO; 4]; 4]
            },
        }
    }
}
