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
//! Hessian of `E` projected to positive semi-definite (in the 9 dimensions off the translations,
//! where it lives); damping is `f = -α H⁺ v`.
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
        psd_off_translations(&self.hessian(s, g, d))
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

/// Three orthonormal 4-vectors orthogonal to `(1, 1, 1, 1)` (a Hadamard basis): with `I₃` they
/// span the motions of a stencil that are not translations.
const OFF_TRANSLATION: [[f64; 4]; 3] = [
    [0.5, 0.5, -0.5, -0.5],
    [0.5, -0.5, 0.5, -0.5],
    [0.5, -0.5, -0.5, 0.5],
];

/// The positive semi-definite projection of a translation-invariant `h` (`h t = 0` for every
/// translation `t`): its eigenvectors of non-zero eigenvalue lie off the translations, so the
/// projection is that of the 9 × 9 `Qᵀ h Q` (`Q = OFF_TRANSLATION ⊗ I₃`), mapped back — the
/// 12 × 12 projection for an eigen-decomposition of 9 × 9, not 12 × 12. (The rounding of `h`
/// along the translations is dropped: the result annihilates them exactly.)
fn psd_off_translations(h: &Matrix12) -> Matrix12 {
    // t = Qᵀ h (9 × 12), then r = t Q (9 × 9)
    let mut t = [[0.0; 12]; 9];
    for (u, basis) in OFF_TRANSLATION.iter().enumerate() {
        for r in 0..3 {
            for (col, out) in t[3 * u + r].iter_mut().enumerate() {
                *out = (0..4).map(|a| basis[a] * h[3 * a + r][col]).sum();
            }
        }
    }
    let mut reduced = [[0.0; 9]; 9];
    for (row, t_row) in reduced.iter_mut().zip(&t) {
        for (w, basis) in OFF_TRANSLATION.iter().enumerate() {
            for c in 0..3 {
                row[3 * w + c] = (0..4).map(|b| t_row[3 * b + c] * basis[b]).sum();
            }
        }
    }
    project_psd::<9>(&mut reduced);
    // h⁺ = Q r⁺ Qᵀ: first Q r⁺ (12 × 9), then times Qᵀ
    let mut qr = [[0.0; 9]; 12];
    for a in 0..4 {
        for r in 0..3 {
            for (col, out) in qr[3 * a + r].iter_mut().enumerate() {
                *out = (0..3)
                    .map(|u| OFF_TRANSLATION[u][a] * reduced[3 * u + r][col])
                    .sum();
            }
        }
    }
    let mut out = [[0.0; 12]; 12];
    for (row, qr_row) in out.iter_mut().zip(&qr) {
        for b in 0..4 {
            for c in 0..3 {
                row[3 * b + c] = (0..3)
                    .map(|w| qr_row[3 * w + c] * OFF_TRANSLATION[w][b])
                    .sum();
            }
        }
    }
    out
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

#[cfg(test)]
mod tests {
    use super::super::Force;
    use super::super::testing::*;
    use super::*;
    use crate::linalg::eigen::symmetric_eigen;
    use crate::mesh::{Face, Mesh};
    use glam::DQuat;
    use proptest::prelude::*;

    /// A hinge with its edge `x0 = 0`, `x1 = (l, 0, 0)` and wings of foot `p` and height `h`
    /// turned by `-φ1` (wing 1) and `+φ2` (wing 2) about the edge from the flat
    /// `x2 = (p1, h1, 0)`, `x3 = (p2, -h2, 0)`: its angle is `φ1 + φ2`.
    fn built(l: f64, [p1, h1, p2, h2]: [f64; 4], [phi1, phi2]: [f64; 2]) -> [Vec3; 4] {
        let turn = |p: f64, y: f64, phi: f64| Vec3::new(p, y * phi.cos(), y * phi.sin());
        [
            Vec3::ZERO,
            Vec3::new(l, 0.0, 0.0),
            turn(p1, h1, -phi1),
            turn(p2, -h2, phi2),
        ]
    }

    /// `x` moved rigidly: rotated by `q`, then shifted by `t`.
    fn moved(x: &[Vec3], q: DQuat, t: Vec3) -> Vec<Vec3> {
        x.iter().map(|&p| q * p + t).collect()
    }

    fn rotation() -> impl Strategy<Value = DQuat> {
        (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64, -PI..PI).prop_filter_map(
            "axis",
            |(a, b, c, ang)| {
                let axis = Vec3::new(a, b, c);
                (axis.length() > 0.1).then(|| DQuat::from_axis_angle(axis.normalize(), ang))
            },
        )
    }

    fn shape() -> impl Strategy<Value = [f64; 4]> {
        (-0.8..1.8f64, 0.15..1.5f64, -0.8..1.8f64, 0.15..1.5f64)
            .prop_map(|(a, b, c, d)| [a, b, c, d])
    }

    /// The angle: uniform in `(-π, π]` or folded over, within 0.3 of `±π`.
    fn angle() -> impl Strategy<Value = f64> {
        prop_oneof![-PI..PI, (PI - 0.3..PI), (-PI..0.3 - PI)]
    }

    /// One hinge (particles 0..4) at a built angle with a rest shape of another shape and
    /// angle, `θ - θ̄` kept 0.2 from the kink at `±π`; moved rigidly.
    fn one_hinge() -> impl Strategy<Value = (Vec<Vec3>, Hinges)> {
        (
            0.3..2.0f64,
            shape(),
            shape(),
            angle(),
            -1.0..1.0f64,
            -2.9..2.9f64,
            rotation(),
            0.01..10.0f64,
        )
            .prop_map(|(l, s, rest_s, theta, split, delta, q, b)| {
                let rest_theta = wrapped(theta - delta, 0.0);
                let x = built(
                    l,
                    s,
                    [(0.5 + 0.3 * split) * theta, (0.5 - 0.3 * split) * theta],
                );
                let rest = built(l * 1.1, rest_s, [0.5 * rest_theta, 0.5 * rest_theta]);
                let x = moved(&x, q, Vec3::new(0.3, -0.2, 0.1));
                (x, Hinges::new(&rest, vec![[0, 1, 2, 3]], vec![b], 0.0))
            })
    }

    fn vec3() -> impl Strategy<Value = Vec3> {
        (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64).prop_map(|(a, b, c)| Vec3::new(a, b, c))
    }

    /// Heights of a hinge's triangles over its edge, over the edge's length.
    fn aspects(x: [Vec3; 4]) -> [f64; 2] {
        let e = x[1] - x[0];
        let l2 = e.length_squared();
        [
            e.cross(x[2] - x[0]).length() / l2,
            e.cross(x[3] - x[0]).length() / l2,
        ]
    }

    /// Two hinges sharing particles (triangles (0,1,2), (0,1,3), (1,2,4)) at random positions,
    /// rest at other random positions; no triangle thinner than 0.1 of its edge, `θ - θ̄` 0.2
    /// from the kink.
    fn two_hinges() -> impl Strategy<Value = (Vec<Vec3>, Hinges)> {
        (
            prop::collection::vec(vec3(), 5),
            prop::collection::vec(vec3(), 5),
            prop::array::uniform2(0.01..10.0f64),
        )
            .prop_filter_map("well shaped", |(x, rest, b)| {
                let stencils = vec![[0, 1, 2, 3], [1, 2, 0, 4]];
                for st in &stencils {
                    for p in [&x, &rest] {
                        let local = st.map(|i| p[i as usize]);
                        if aspects(local).iter().any(|&a| a < 0.1)
                            || (local[1] - local[0]).length() < 0.1
                        {
                            return None;
                        }
                    }
                }
                let h = Hinges::new(&rest, stencils, b.to_vec(), 0.0);
                for s in 0..2 {
                    let (_, d) = h.eval(s, &x)?;
                    if d.abs() > PI - 0.2 {
                        return None;
                    }
                }
                Some((x, h))
            })
    }

    /// The exact Hessian of a one-hinge force, densely.
    fn exact_hessian(h: &Hinges, x: &[Vec3]) -> Vec<Vec<f64>> {
        let (g, d) = h.eval(0, x).expect("not degenerate");
        h.hessian(0, &g, d).iter().map(|r| r.to_vec()).collect()
    }

    fn max_abs(m: &[Vec<f64>]) -> f64 {
        m.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()))
    }

    fn eigenvalues<const N: usize>(m: &[Vec<f64>]) -> [f64; N] {
        let a: [[f64; N]; N] = std::array::from_fn(|i| std::array::from_fn(|j| m[i][j]));
        symmetric_eigen::<N>(&a).0
    }

    fn force_is_minus_energy_gradient(h: &Hinges, x: &[Vec3]) -> Result<(), TestCaseError> {
        let mut f = vec![Vec3::ZERO; x.len()];
        h.add_force(&at(x, x), &mut f);
        let fd = fd_gradient(h, x);
        let scale = f.iter().fold(1e-3f64, |m, v| m.max(v.length()));
        for i in 0..x.len() {
            prop_assert!(
                (f[i] - fd[i]).length() < 1e-5 * scale,
                "{i}: {:?} vs {:?}",
                f[i],
                fd[i]
            );
        }
        Ok(())
    }

    /// `-K = H⁺` symmetric and positive semi-definite, `n` particles.
    fn matrix_is_symmetric_psd<const N: usize>(
        h: &Hinges,
        x: &[Vec3],
    ) -> Result<(), TestCaseError> {
        let k = assembled(h, x, x, 1.0, 0.0);
        let scale = max_abs(&k).max(1e-300);
        for r in 0..N {
            for c in 0..N {
                prop_assert!((k[r][c] - k[c][r]).abs() <= 1e-12 * scale);
            }
        }
        let minus: Vec<Vec<f64>> = k.iter().map(|r| r.iter().map(|v| -v).collect()).collect();
        let lambda = eigenvalues::<N>(&minus);
        prop_assert!(lambda.iter().all(|&l| l >= -1e-9 * scale), "{lambda:?}");
        prop_assert!(check_product(h, x, x, 1.0, 0.0, x) < 1e-12);
        Ok(())
    }

    proptest! {
        #[test]
        fn hinge_force_is_minus_the_energy_gradient((x, h) in one_hinge()) {
            force_is_minus_energy_gradient(&h, &x)?;
        }

        #[test]
        fn hinge_force_is_minus_the_energy_gradient_on_shared_particles((x, h) in two_hinges()) {
            force_is_minus_energy_gradient(&h, &x)?;
        }

        /// The exact Hessian (before the projection) against central differences of the force,
        /// and the closed form of `∇²θ` symmetric block by block (the matrix uses its upper
        /// blocks only).
        #[test]
        fn hinge_exact_hessian_is_the_derivative_of_the_force((x, h) in one_hinge()) {
            let fd = fd_jacobian(&h, &x, &x, false);
            let minus_h: Vec<Vec<f64>> = exact_hessian(&h, &x).iter().map(|r| r.iter().map(|v| -v).collect()).collect();
            prop_assert!(rel_diff(&minus_h, &fd) < 1e-6, "rel diff {}", rel_diff(&minus_h, &fd));
            let (g, _) = h.eval(0, &x).unwrap();
            let scale = (0..4).flat_map(|i| (0..4).map(move |j| (i, j)))
                .fold(0.0f64, |m, (i, j)| m.max(crate::math::max_abs(&g.hessian_block(i, j))));
            for i in 0..4 { for j in 0..4 {
                let diff = g.hessian_block(i, j) - g.hessian_block(j, i).transpose();
                prop_assert!(crate::math::max_abs(&diff) < 1e-12 * scale, "block {i} {j}");
            }}
        }

        #[test]
        fn hinge_matrix_is_symmetric_and_minus_it_positive_semidefinite((x, h) in one_hinge()) {
            matrix_is_symmetric_psd::<12>(&h, &x)?;
            // and it is the exact Hessian wherever that is already positive semi-definite
            let exact = exact_hessian(&h, &x);
            if eigenvalues::<12>(&exact).iter().all(|&l| l >= 0.0) {
                let minus_k: Vec<Vec<f64>> = assembled(&h, &x, &x, 1.0, 0.0).iter().map(|r| r.iter().map(|v| -v).collect()).collect();
                prop_assert!(rel_diff(&minus_k, &exact) < 1e-12);
            }
        }

        /// The projection off the translations is the 12 × 12 projection of the exact Hessian.
        #[test]
        fn hinge_projection_off_translations_is_the_full_projection((x, h) in one_hinge()) {
            let (g, d) = h.eval(0, &x).unwrap();
            let mut full = h.hessian(0, &g, d);
            project_psd::<12>(&mut full);
            let reduced = h.projected(0, &g, d);
            let (full, reduced): (Vec<Vec<f64>>, Vec<Vec<f64>>) =
                (full.iter().map(|r| r.to_vec()).collect(), reduced.iter().map(|r| r.to_vec()).collect());
            prop_assert!(rel_diff(&reduced, &full) < 1e-9, "{}", rel_diff(&reduced, &full));
        }

        #[test]
        fn hinge_assembled_matrix_on_shared_particles_is_symmetric_and_semidefinite((x, h) in two_hinges()) {
            matrix_is_symmetric_psd::<15>(&h, &x)?;
        }

        /// `∂f/∂v = -α H⁺` against central differences, `-∂Ψ/∂v` = the damping force, and the
        /// damping takes power out.
        #[test]
        fn hinge_damping_is_the_velocity_derivative_of_its_dissipation(
            (x, mut h) in two_hinges(), v in prop::collection::vec(vec3(), 5), alpha in 0.001..0.5f64,
        ) {
            h.damping = alpha;
            let got = assembled(&h, &x, &v, 0.0, 1.0);
            // linear in v: a step of 1 m/s (see `fd_jacobian_step`)
            let fd = fd_jacobian_step(&h, &x, &v, true, 1.0);
            prop_assert!(rel_diff(&got, &fd) < 1e-7, "{}", rel_diff(&got, &fd));
            let mut f = vec![Vec3::ZERO; 5];
            h.add_force(&at(&x, &v), &mut f);
            let mut f0 = vec![Vec3::ZERO; 5];
            h.add_force(&at(&x, &[Vec3::ZERO; 5]), &mut f0);
            let mut vp = v.clone();
            let scale = f.iter().zip(&f0).fold(1e-6f64, |m, (a, b)| m.max((*a - *b).length()));
            for i in 0..5 { for k in 0..3 {
                let e = 1e-6;
                vp[i][k] = v[i][k] + e; let p = h.dissipation(&at(&x, &vp));
                vp[i][k] = v[i][k] - e; let m = h.dissipation(&at(&x, &vp));
                vp[i][k] = v[i][k];
                prop_assert!((-(p - m) / (2.0 * e) - (f[i][k] - f0[i][k])).abs() < 1e-6 * scale);
            }}
            let power: f64 = f.iter().zip(&f0).zip(&v).map(|((a, b), u)| (*a - *b).dot(*u)).sum();
            prop_assert!(power <= 1e-12 * scale);
            prop_assert!(h.dissipation(&at(&x, &v)) >= 0.0);
        }

        /// The fused evaluation against the three calls, bit for bit, with and without damping
        /// and with a degenerate hinge (`collapse`: a wing folded onto the edge).
        #[test]
        fn hinge_linearization_has_the_bits_of_the_separate_calls(
            (mut x, mut h) in two_hinges(),
            damped in any::<bool>(),
            collapse in any::<bool>(),
            a in -2.0..2.0f64,
            b in -2.0..2.0f64,
            v in prop::collection::vec(vec3(), 5),
            w in prop::collection::vec(vec3(), 5),
        ) {
            h.damping = if damped { 0.05 } else { 0.0 };
            if collapse {
                x[3] = 0.5 * (x[0] + x[1]);
            }
            let at = Linearization { t: T, x: &x, v: &v, matrix: (a, b), product: (b, a), w: &w };
            prop_assert!(linearization_is_bitwise_separate(&h, &at, &w));
        }

        /// At rest (flat or bent) no force; moved rigidly, the same energy and still no force.
        #[test]
        fn hinge_rest_shape_is_force_free_and_energy_is_rigid_invariant(
            (x, h) in one_hinge(), rest_s in shape(), rest_theta in angle(), q in rotation(), t in vec3(),
        ) {
            let rest = built(0.7, rest_s, [0.4 * rest_theta, 0.6 * rest_theta]);
            let at_rest = Hinges::new(&rest, vec![[0, 1, 2, 3]], vec![2.0], 0.0);
            let mut f = vec![Vec3::ZERO; 4];
            at_rest.add_force(&at(&rest, &rest), &mut f);
            prop_assert!(f.iter().all(|v| *v == Vec3::ZERO));
            prop_assert_eq!(at_rest.energy(T, &rest), 0.0);
            let rest_moved = moved(&rest, q, t);
            let mut f = vec![Vec3::ZERO; 4];
            at_rest.add_force(&at(&rest_moved, &rest_moved), &mut f);
            let k = at_rest.stiffness[0];
            prop_assert!(f.iter().all(|v| v.length() < 1e-12 * k * 100.0), "{f:?}");
            let e = h.energy(T, &x);
            let e_moved = h.energy(T, &moved(&x, q, t));
            prop_assert!((e - e_moved).abs() <= 1e-10 * e.max(1e-3 * h.stiffness[0]), "{e} vs {e_moved}");
        }
    }

    #[test]
    fn dihedral_angle_of_hinges_built_at_known_angles() {
        let q = DQuat::from_axis_angle(Vec3::new(1.0, 2.0, -0.5).normalize(), 1.1);
        for degrees in [0.0, 30.0, 90.0, 170.0, -60.0, -179.0, 179.5] {
            let theta = f64::to_radians(degrees);
            for split in [0.5, 0.0, 1.0, 0.2] {
                for s in [[0.3, 0.5, 0.6, 0.4], [-0.5, 0.2, 1.4, 1.1]] {
                    let x = built(1.3, s, [split * theta, (1.0 - split) * theta]);
                    let x = moved(&x, q, Vec3::new(2.0, -1.0, 0.5));
                    let got = dihedral_angle([x[0], x[1], x[2], x[3]]).unwrap();
                    assert!(
                        (got - theta).abs() < 1e-12,
                        "{degrees}°: {}",
                        got.to_degrees()
                    );
                }
            }
        }
        // a wing turned by -φ about its own edge raises the angle, whichever wing: ridges are
        // positive seen from the side n1 = e × (x2 - x0) points to (here +z)
        let ridge = [
            Vec3::ZERO,
            Vec3::X,
            Vec3::new(0.5, 1.0, -0.1),
            Vec3::new(0.5, -1.0, -0.1),
        ];
        assert!(dihedral_angle(ridge).unwrap() > 0.0);
        let valley = ridge.map(|p| Vec3::new(p.x, p.y, -p.z));
        assert!(dihedral_angle(valley).unwrap() < 0.0);
    }

    #[test]
    fn degenerate_hinges_exert_nothing_and_never_give_nan() {
        let ok = built(1.0, [0.3, 0.5, 0.6, 0.4], [0.2, 0.3]);
        let rest = built(1.0, [0.3, 0.5, 0.6, 0.4], [0.0, 0.0]);
        let h = Hinges::new(&rest, vec![[0, 1, 2, 3]], vec![1.0], 0.1);
        let mut cases = vec![
            [ok[0], ok[0], ok[2], ok[3]],       // no edge
            [ok[0], ok[1], 0.3 * ok[1], ok[3]], // wing 1 on the edge line
            [ok[0], ok[1], ok[2], ok[0]],       // wing 2 on x0
            [ok[0], ok[1], ok[2], ok[3] + Vec3::new(f64::NAN, 0.0, 0.0)],
        ];
        cases.push([Vec3::ZERO; 4]);
        for x in cases {
            assert_eq!(h.energy(T, &x), 0.0);
            let mut f = vec![Vec3::ZERO; 4];
            h.add_force(&at(&x, &ok), &mut f);
            assert!(f.iter().all(|v| *v == Vec3::ZERO));
            assert!(
                assembled(&h, &x, &ok, 1.0, 1.0)
                    .iter()
                    .flatten()
                    .all(|&v| v == 0.0)
            );
        }
        // degenerate at rest: inactive, not infinite
        let flat = [Vec3::ZERO, Vec3::X, 0.5 * Vec3::X, Vec3::Y];
        let dead = Hinges::new(&flat, vec![[0, 1, 2, 3]], vec![1.0], 0.0);
        assert_eq!(dead.stiffness[0], 0.0);
        assert_eq!(dead.energy(T, &ok), 0.0);
    }

    #[test]
    fn rigidity_across_an_edge_interpolates_warp_and_weft() {
        let b = [2.0, 5.0];
        // an edge along the weft is bent across by curvature along the warp
        assert_eq!(rigidity_across([0.0, 0.3], b), 2.0);
        assert_eq!(rigidity_across([-0.7, 0.0], b), 5.0);
        assert!((rigidity_across([1.0, 1.0], b) - 3.5).abs() < 1e-15);
        let (c, s) = (0.3f64.cos(), 0.3f64.sin());
        // across direction (c, s) ⇒ edge (-s, c)
        assert!((rigidity_across([-s, c], b) - (2.0 * c * c + 5.0 * s * s)).abs() < 1e-14);
        assert_eq!(rigidity_across([0.0, 0.0], b), 3.5);
    }

    /// The triangles of an `n × n` grid: quads split along one diagonal (`0`), the other (`1`),
    /// or alternating (`2`).
    fn grid_triangles(mesh: &Mesh, split: usize) -> Vec<[u32; 3]> {
        let mut tris = Vec::new();
        for (q, face) in mesh.faces.iter().enumerate() {
            let Face::Quad([a, b, c, d]) = *face else {
                unreachable!()
            };
            let one = split == 0 || (split == 2 && (q + q / 7) % 2 == 0);
            if one {
                tris.extend(face.triangles());
            } else {
                tris.extend([[a, b, d], [b, c, d]]);
            }
        }
        tris
    }

    /// A 1 m × 1 m sheet in the plane z = 0 with `n × n` vertices, interior vertices moved by up
    /// to `jitter` spacings in x and y (a fixed pseudo-random sequence).
    fn sheet(n: usize, split: usize, jitter: f64) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let mesh = Mesh::grid([1.0, 1.0], [n, n], Vec3::ZERO, Vec3::Z).unwrap();
        let spacing = 1.0 / (n - 1) as f64;
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut uniform = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let mut x = mesh.positions.clone();
        for (i, p) in x.iter_mut().enumerate() {
            let (r, c) = (i / n, i % n);
            let (dx, dy) = (uniform(), uniform());
            if r > 0 && r + 1 < n && c > 0 && c + 1 < n {
                *p += jitter * spacing * Vec3::new(dx, dy, 0.0);
            }
        }
        (x, grid_triangles(&mesh, split))
    }

    /// The sheet rolled without stretch onto a cylinder of radius `r`, curved along x
    /// (`axis = 0`) or along y (`axis = 1`).
    fn rolled(x: &[Vec3], r: f64, axis: usize) -> Vec<Vec3> {
        x.iter()
            .map(|p| {
                let (along, across) = if axis == 0 { (p.x, p.y) } else { (p.y, p.x) };
                let (a, z) = (r * (along / r).sin(), r * (1.0 - (along / r).cos()));
                if axis == 0 {
                    Vec3::new(a, across, z)
                } else {
                    Vec3::new(across, a, z)
                }
            })
            .collect()
    }

    /// Energy of the rolled sheet over `½ B / R²` times (the total area, the area the hinges
    /// stand for, `Σ (Ā1 + Ā2) / 3`), warp along x; `bent` is the rigidity the bend should see.
    fn cylinder_ratios(
        n: usize,
        split: usize,
        jitter: f64,
        rigidity: [f64; 2],
        axis: usize,
    ) -> (f64, f64) {
        let (flat, tris) = sheet(n, split, jitter);
        let edges = interior_edges(&tris);
        let stencils: Vec<[u32; 4]> = edges.iter().map(|e| e.0).collect();
        let b: Vec<f64> = stencils
            .iter()
            .map(|s| {
                let e = flat[s[1] as usize] - flat[s[0] as usize];
                rigidity_across([e.x, e.y], rigidity)
            })
            .collect();
        let area_of = |t: &[u32; 3]| {
            let p = t.map(|i| flat[i as usize]);
            0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length()
        };
        let area: f64 = tris.iter().map(area_of).sum();
        let hinge_area: f64 = edges
            .iter()
            .map(|(_, [t1, t2])| (area_of(&tris[*t1]) + area_of(&tris[*t2])) / 3.0)
            .sum();
        let h = Hinges::new(&flat, stencils, b, 0.0);
        let r = 0.4;
        let e = h.energy(T, &rolled(&flat, r, axis));
        let per_area = 0.5 * rigidity[axis] / (r * r);
        (e / (per_area * area), e / (per_area * hinge_area))
    }

    /// The constant: on regular triangulations (either diagonal, or mixed) bent along either
    /// axis, the interior hinges carry exactly the continuum `½ B κ²` per unit area; the
    /// boundary strip, whose edges have no hinge, makes the total converge as `1/n`.
    #[test]
    fn a_sheet_rolled_onto_a_cylinder_has_the_continuum_bending_energy() {
        for split in 0..3 {
            for axis in 0..2 {
                let mut last = f64::INFINITY;
                for n in [9, 17, 33] {
                    let (total, hinged) = cylinder_ratios(n, split, 0.0, [0.02, 0.02], axis);
                    let error = (total - 1.0).abs();
                    assert!(
                        error < 0.6 * last,
                        "split {split} axis {axis} n {n}: {total}"
                    );
                    last = error;
                    // the boundary strip: n - 2 of the n - 1 columns of hinges, of
                    // n - 5/3 columns' worth of hinge area
                    let nn = n as f64;
                    assert!((total - (nn - 2.0) / (nn - 1.0)).abs() < 1e-9, "{total}");
                    assert!(
                        (hinged - (nn - 2.0) / (nn - 5.0 / 3.0)).abs() < 1e-9,
                        "{hinged}"
                    );
                }
                assert!(last < 0.035);
            }
        }
    }

    /// Jittered (irregular) triangulations: within a few % too. The discrete-shells energy is
    /// known not to converge to the continuum on irregular meshes: the excess depends on the
    /// irregularity (about quadratically), not on the spacing.
    #[test]
    fn a_jittered_sheet_rolled_onto_a_cylinder_has_nearly_the_continuum_energy() {
        for split in 0..3 {
            for axis in 0..2 {
                let coarse = cylinder_ratios(17, split, 0.1, [0.02, 0.02], axis).1;
                let fine = cylinder_ratios(33, split, 0.1, [0.02, 0.02], axis).1;
                let finer = cylinder_ratios(65, split, 0.1, [0.02, 0.02], axis).1;
                for (n, ratio) in [(17, coarse), (33, fine), (65, finer)] {
                    assert!(
                        (ratio - 1.0).abs() < 0.05,
                        "split {split} axis {axis} n {n}: {ratio}"
                    );
                }
                assert!((finer - fine).abs() < 0.01, "{fine} {finer}");
            }
        }
    }

    /// Anisotropy: bent along the warp (x) the sheet has `B_warp`'s energy, along the weft
    /// `B_weft`'s, the other rigidity 4 times larger or smaller.
    #[test]
    fn a_sheet_bent_along_warp_or_weft_takes_that_rigidity() {
        for rigidity in [[0.01, 0.04], [0.04, 0.01]] {
            for split in 0..3 {
                for axis in 0..2 {
                    let regular = cylinder_ratios(33, split, 0.0, rigidity, axis).1;
                    assert!(
                        (regular - 1.0).abs() < 0.015,
                        "{rigidity:?} split {split} axis {axis}: {regular}"
                    );
                    let jittered = cylinder_ratios(33, split, 0.05, rigidity, axis).1;
                    assert!(
                        (jittered - 1.0).abs() < 0.05,
                        "{rigidity:?} split {split} axis {axis}: {jittered}"
                    );
                }
            }
        }
    }

    #[test]
    fn interior_edges_of_a_grid_match_euler_and_face_their_opposite_vertices() {
        for (nx, ny) in [(2, 2), (5, 4), (7, 9)] {
            for split in 0..3 {
                let mesh = Mesh::grid([1.0, 1.0], [nx, ny], Vec3::ZERO, Vec3::Z).unwrap();
                let tris = grid_triangles(&mesh, split);
                let edges = interior_edges(&tris);
                let (v, t) = ((nx * ny) as i64, tris.len() as i64);
                let boundary = 2 * (nx as i64 - 1) + 2 * (ny as i64 - 1);
                // a disk: V - E + F = 1, and 3F = 2 I + B
                let all = v + t - 1;
                assert_eq!(edges.len() as i64, all - boundary);
                assert_eq!(2 * edges.len() as i64, 3 * t - boundary);
                let mut seen = std::collections::HashSet::new();
                for &([a, b, c, d], [t1, t2]) in &edges {
                    assert!(t1 < t2);
                    assert!(seen.insert((a.min(b), a.max(b))), "edge twice");
                    let has = |tri: [u32; 3], p: [u32; 3]| p.iter().all(|q| tri.contains(q));
                    assert!(has(tris[t1], [a, b, c]) && has(tris[t2], [a, b, d]));
                    assert!(c != d && ![a, b].contains(&c) && ![a, b].contains(&d));
                }
                assert_eq!(edges, interior_edges(&tris));
                // and a flat grid is at rest: every hinge's angle 0
                for &(s, _) in &edges {
                    let theta = dihedral_angle(s.map(|i| mesh.positions[i as usize])).unwrap();
                    assert!(theta.abs() < 1e-12);
                }
            }
        }
    }

    #[test]
    fn interior_edges_skip_boundary_non_manifold_and_repeated_triangles() {
        assert!(interior_edges(&[[0, 1, 2]]).is_empty());
        // three triangles on edge 0-1: no hinge there; the others are boundary edges
        assert!(interior_edges(&[[0, 1, 2], [1, 0, 3], [0, 1, 4]]).is_empty());
        // the same triangle twice, and a triangle with a repeated vertex
        assert!(interior_edges(&[[0, 1, 2], [1, 0, 2]]).is_empty());
        assert_eq!(
            interior_edges(&[[0, 1, 1], [0, 1, 2], [1, 0, 3]]),
            vec![([0, 1, 2, 3], [1, 2])]
        );
    }
}
