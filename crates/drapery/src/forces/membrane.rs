//! The shell membrane, docs/MATH.md §20: an orthotropic St. Venant–Kirchhoff membrane on
//! triangles, in plane stress, written in each rest triangle's material frame (axis 1 = warp,
//! axis 2 = weft).
//!
//! Per triangle with rest coordinates `r_0, r_1, r_2` (material frame, m): `D_m = [r_1 - r_0,
//! r_2 - r_0]`, `F = [x_1 - x_0, x_2 - x_0] D_m⁻¹` (3×2), `E = ½ (FᵀF - I)`, energy `A W(E)` with
//! `W = ½ (C11 E11² + 2 C12 E11 E22 + C22 E22²) + 2 G E12²`, plus a compression term on
//! principal stretches below 0.8 that keeps the stiffness positive under strong compression
//! (MATH §20, "Compression": exactly St Venant–Kirchhoff above). The force is `-∇(A W)` exactly;
//! the matrix uses the Hessian with `∂²W/∂F²` (6×6) projected to positive semi-definite, so
//! `-K` is positive semi-definite at every configuration. Stiffness-proportional damping
//! `f = -α H⁺ v` (the projected Hessian) has the dissipation potential `Ψ = ½ α vᵀ H⁺ v`.

use super::stencil::{Full, Gather, Local, StencilForce};
use super::{Linearization, State};
use crate::linalg::eigen::project_psd;
use crate::math::{Mat3, Vec3, outer};

/// An orthotropic plane-stress membrane law, moduli per unit rest length (N/m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MembraneLaw {
    /// Stretch moduli `[Y1, Y2]` along the warp and the weft, N/m.
    pub stretch_modulus: [f64; 2],
    /// Poisson ratio `ν = ν12` (weft contraction under warp stress); `ν21 = ν Y2 / Y1`.
    pub poisson: f64,
    /// In-plane shear modulus `G`, N/m.
    pub shear_modulus: f64,
}

impl MembraneLaw {
    /// The default shear modulus `Y / (2 (1 + ν))` with `Y = √(Y1 Y2)`: the isotropic value
    /// when `Y1 = Y2`.
    pub fn isotropic_shear(stretch_modulus: [f64; 2], poisson: f64) -> f64 {
        (stretch_modulus[0] * stretch_modulus[1]).sqrt() / (2.0 * (1.0 + poisson))
    }

    /// Whether the law is a stable material: finite positive moduli and `ν12 ν21 < 1` (so the
    /// plane-stress stiffness is positive definite). [`Membrane`] assumes it.
    pub fn is_stable(&self) -> bool {
        let [y1, y2] = self.stretch_modulus;
        let (nu, g) = (self.poisson, self.shear_modulus);
        let positive = |v: f64| v > 0.0 && v.is_finite();
        positive(y1) && positive(y2) && positive(g) && nu.is_finite() && nu * nu * y2 / y1 < 1.0
    }

    /// The plane-stress constants.
    fn constants(&self) -> Constants {
        let [y1, y2] = self.stretch_modulus;
        let nu12 = self.poisson;
        let nu21 = nu12 * y2 / y1;
        let c11 = y1 / (1.0 - nu12 * nu21);
        Constants {
            c11,
            c12: nu21 * c11,
            c22: y2 / (1.0 - nu12 * nu21),
            g: self.shear_modulus,
        }
    }
}

/// `C11, C12, C22, G` of a [`MembraneLaw`], N/m.
#[derive(Clone, Copy, Debug)]
struct Constants {
    c11: f64,
    c12: f64,
    c22: f64,
    g: f64,
}

impl Constants {
    /// `k = max(C11, C22, C12 + 2G)`: the greatest modulus `W''(E)` of the law under a
    /// uniaxial strain `E = e n nᵀ` along any direction `n` (§20, compression).
    fn compression_modulus(&self) -> f64 {
        self.c11.max(self.c22).max(self.c12 + 2.0 * self.g)
    }
}

/// The principal stretch below which the compression term acts (§20).
pub const COMPRESSION_STRETCH: f64 = 0.8;

/// The compression term `ψ(s) = (k/8) δ³ (4 s₀ − δ)`, `δ = s₀ − s`, of one principal stretch
/// `s < s₀` and its first two derivatives in `s` (all three 0 at `s ≥ s₀`).
fn compression_term(k: f64, s: f64) -> [f64; 3] {
    let s0 = COMPRESSION_STRETCH;
    let d = (s0 - s).max(0.0);
    [
        0.125 * k * d * d * d * (4.0 * s0 - d),
        -0.5 * k * d * d * (3.0 * s0 - d),
        1.5 * k * d * (2.0 * s0 - d),
    ]
}

/// The compression term of a triangle with a principal stretch below
/// [`COMPRESSION_STRETCH`]: what it adds to the energy, and the parts of its `∂²W/∂F²` beyond
/// its stress (which is folded into [`Strain::s`]).
#[derive(Clone, Copy, Debug)]
struct Compression {
    /// `Σ_i ψ(s_i)`, J/m².
    energy: f64,
    /// Per principal direction `i`: `ψ''(s_i) − ψ'(s_i)/s_i ≥ 0` and the 6-vector
    /// `n_i = [v_i1 û_i, v_i2 û_i]`, `û_i = F v_i / s_i`.
    along: [(f64, [Vec3; 2]); 2],
    /// `2θ = (g_1 − g_2)/(λ_1 − λ_2) ≥ 0`, `g_i = ψ'(s_i)/s_i`, and the 6-vector
    /// `m = [v_21 u_1 + v_11 u_2, v_22 u_1 + v_12 u_2]`, `u_i = F v_i`.
    across: (f64, [Vec3; 2]),
}

/// The compression term of `F = [f_1, f_2]` for modulus `k`, and the stress `2 ∂Ψ/∂C` it adds
/// (`[S11, S12, S22]`); `None` when both principal stretches are at least
/// [`COMPRESSION_STRETCH`].
fn compression(k: f64, f: [Vec3; 2]) -> Option<(Compression, [f64; 3])> {
    let s0 = COMPRESSION_STRETCH;
    let (c11, c12, c22) = (f[0].dot(f[0]), f[0].dot(f[1]), f[1].dot(f[1]));
    let half = 0.5 * (c11 + c22);
    let r = (0.25 * (c11 - c22).powi(2) + c12 * c12).sqrt();
    let l2 = half + r;
    // λ_1 = det C / λ_2, det C = |f_1 × f_2|², without the cancellation of `half − r`
    let l1 = if l2 > 0.0 {
        f[0].cross(f[1]).length_squared() / l2
    } else {
        0.0
    };
    if l1 >= s0 * s0 {
        return None;
    }
    // eigenvectors: v_1 for λ_1 from the longer of the two rows' null vectors
    let v1 = {
        let a = [c12, l1 - c11];
        let b = [l1 - c22, c12];
        let (na, nb) = (a[0] * a[0] + a[1] * a[1], b[0] * b[0] + b[1] * b[1]);
        let (v, n) = if na >= nb { (a, na) } else { (b, nb) };
        if n > 0.0 {
            let n = n.sqrt();
            [v[0] / n, v[1] / n]
        } else {
            [1.0, 0.0]
        }
    };
    let v = [v1, [-v1[1], v1[0]]];
    let lambda = [l1, l2];
    let mut energy = 0.0;
    let mut stress = [0.0; 3];
    let mut g = [0.0; 2];
    let mut a = [0.0; 2];
    let mut u = [Vec3::ZERO; 2];
    let mut along = [(0.0, [Vec3::ZERO; 2]); 2];
    for i in 0..2 {
        // a floor on s keeps a triangle collapsed onto a line finite (its direction is then
        // arbitrary, like a spring's of zero length)
        let st = lambda[i].sqrt().max(1e-12 * s0);
        let [psi, d1, d2] = compression_term(k, st);
        energy += psi;
        g[i] = d1 / st;
        a[i] = d2 - d1 / st;
        u[i] = v[i][0] * f[0] + v[i][1] * f[1];
        stress[0] += g[i] * v[i][0] * v[i][0];
        stress[1] += g[i] * v[i][0] * v[i][1];
        stress[2] += g[i] * v[i][1] * v[i][1];
        let uhat = u[i] / st;
        along[i] = (a[i], [v[i][0] * uhat, v[i][1] * uhat]);
    }
    let gap = lambda[1] - lambda[0];
    let theta2 = if gap > 1e-9 * lambda[1] {
        (g[0] - g[1]) / (lambda[0] - lambda[1])
    } else {
        // the limit 2φ''(λ) = (ψ'' − ψ'/s)/(2 s²)
        let s = (0.5 * (lambda[0] + lambda[1])).sqrt().max(1e-12 * s0);
        let [_, d1, d2] = compression_term(k, s);
        (d2 - d1 / s) / (2.0 * s * s)
    };
    let m = [
        v[1][0] * u[0] + v[0][0] * u[1],
        v[1][1] * u[0] + v[0][1] * u[1],
    ];
    Some((
        Compression {
            energy,
            along,
            across: (theta2, m),
        },
        stress,
    ))
}

/// One triangle, precomputed from its rest shape.
#[derive(Clone, Copy, Debug)]
struct Element {
    /// Particles.
    tri: [u32; 3],
    /// Rows 0 and 1 of `D_m⁻¹`: the material gradients of the shape functions of particles 1
    /// and 2 (particle 0's is minus their sum), so `F e_a = Σ_i grad[i-1][a] (x_i - x_0)`.
    grad: [[f64; 2]; 2],
    /// Rest area, m² (0 for a degenerate rest triangle, which then does nothing).
    area: f64,
}

/// A 6×6 matrix over the two columns of `F`, as 3×3 blocks `[a][b]` (`∂²W/∂f_a∂f_b`).
type Blocks2 = [[Mat3; 2]; 2];

/// The state of one triangle: `F`'s columns, Green strain and second Piola–Kirchhoff stress.
#[derive(Clone, Copy, Debug)]
struct Strain {
    /// Columns `f_1, f_2` of `F`.
    f: [Vec3; 2],
    /// `[E11, E12, E22]`.
    e: [f64; 3],
    /// `[S11, S12, S22]`, the compression term's included.
    s: [f64; 3],
    /// The compression term, when a principal stretch is below [`COMPRESSION_STRETCH`].
    compression: Option<Compression>,
}

/// The membrane force on a set of triangles, with stiffness-proportional damping.
#[derive(Clone, Debug)]
pub struct Membrane {
    elements: Vec<Element>,
    law: MembraneLaw,
    constants: Constants,
    /// Stiffness-proportional damping `α`, s.
    damping: f64,
    /// Gather lists for the parallel sums.
    sums: Gather<Full<3>>,
}

impl Membrane {
    /// The membrane on `triangles` with rest coordinates `rest` in each triangle's material
    /// frame (see [`material_coordinates`]), law `law` (assumed [`MembraneLaw::is_stable`])
    /// and stiffness-proportional damping `damping` (s). A rest triangle of (nearly) zero area
    /// contributes nothing. `rest` has one entry per triangle.
    pub fn new(
        triangles: Vec<[u32; 3]>,
        rest: Vec<[[f64; 2]; 3]>,
        law: MembraneLaw,
        damping: f64,
    ) -> Membrane {
        assert_eq!(triangles.len(), rest.len(), "one rest shape per triangle");
        let elements = triangles
            .iter()
            .zip(&rest)
            .map(|(&tri, r)| element(tri, r))
            .collect();
        Membrane {
            elements,
            law,
            constants: law.constants(),
            damping,
            sums: Gather::default(),
        }
    }

    /// The law.
    pub fn law(&self) -> MembraneLaw {
        self.law
    }

    /// The damping `α`, s.
    pub fn damping(&self) -> f64 {
        self.damping
    }

    /// Rest area of triangle `s`, m².
    pub fn rest_area(&self, s: usize) -> f64 {
        self.elements[s].area
    }

    /// `F`, `E` and `S` of triangle `el` at `x`.
    #[inline]
    fn strain(&self, el: &Element, x: &[Vec3]) -> Strain {
        let c = &self.constants;
        let f = columns(el, x);
        let e11 = 0.5 * (f[0].dot(f[0]) - 1.0);
        let e22 = 0.5 * (f[1].dot(f[1]) - 1.0);
        let e12 = 0.5 * f[0].dot(f[1]);
        let mut s = [
            c.c11 * e11 + c.c12 * e22,
            2.0 * c.g * e12,
            c.c12 * e11 + c.c22 * e22,
        ];
        let compression = (el.area > 0.0)
            .then(|| compression(c.compression_modulus(), f))
            .flatten()
            .map(|(comp, extra)| {
                s = [s[0] + extra[0], s[1] + extra[1], s[2] + extra[2]];
                comp
            });
        Strain {
            f,
            e: [e11, e12, e22],
            s,
            compression,
        }
    }

    /// `∂²W/∂F²` at `st`, exact, as 3×3 blocks (block `[1][0]` is block `[0][1]` transposed,
    /// bit for bit, and the diagonal blocks are symmetric).
    #[inline]
    fn density_hessian(&self, st: &Strain) -> Blocks2 {
        let c = &self.constants;
        let [f1, f2] = st.f;
        let [s11, s12, s22] = st.s;
        let (f11, f22) = (outer(f1, f1), outer(f2, f2));
        let diag = |s: f64| Mat3::from_diagonal(Vec3::splat(s));
        let h11 = diag(s11) + c.c11 * f11 + c.g * f22;
        let h22 = diag(s22) + c.c22 * f22 + c.g * f11;
        let h12 = diag(s12) + c.c12 * outer(f1, f2) + c.g * outer(f2, f1);
        let mut h = [[h11, h12], [h12.transpose(), h22]];
        if let Some(comp) = &st.compression {
            let (theta2, m) = comp.across;
            for (coef, n) in comp.along.into_iter().chain([(theta2, m)]) {
                h[0][0] += coef * outer(n[0], n[0]);
                h[1][1] += coef * outer(n[1], n[1]);
                h[0][1] += coef * outer(n[0], n[1]);
            }
            h[1][0] = h[0][1].transpose();
        }
        h
    }

    /// `∂²W/∂F²` projected to positive semi-definite. When `S` is positive semi-definite the
    /// exact one already is (`S ⊗ I` plus a sum of positive terms, §20) and is returned as it
    /// is; otherwise it goes through [`project_psd`].
    #[inline]
    fn projected_hessian(&self, st: &Strain) -> Blocks2 {
        let h = self.density_hessian(st);
        let [s11, s12, s22] = st.s;
        if s11 >= 0.0 && s22 >= 0.0 && s11 * s22 >= s12 * s12 {
            return h;
        }
        let mut m = [[0.0; 6]; 6];
        for (a, row) in h.iter().enumerate() {
            for (b, blk) in row.iter().enumerate() {
                for c in 0..3 {
                    let col = blk.col(c);
                    for r in 0..3 {
                        m[3 * a + r][3 * b + c] = col[r];
                    }
                }
            }
        }
        project_psd::<6>(&mut m);
        std::array::from_fn(|a| {
            std::array::from_fn(|b| {
                Mat3::from_cols_array(&std::array::from_fn(|k| m[3 * a + k % 3][3 * b + k / 3]))
            })
        })
    }

    /// `A W` of triangle `el` at strain `st`.
    #[inline]
    fn energy_of(&self, el: &Element, st: &Strain) -> f64 {
        let c = &self.constants;
        let [e11, e12, e22] = st.e;
        let w = 0.5 * (c.c11 * e11 * e11 + 2.0 * c.c12 * e11 * e22 + c.c22 * e22 * e22)
            + 2.0 * c.g * e12 * e12;
        el.area * (w + st.compression.map_or(0.0, |comp| comp.energy))
    }

    /// The energy Hessian blocks `scale · A Gᵀ h G` over the triangle's particles, for a
    /// `∂²W/∂F²` `h` (`G` the linear map from positions to `F`): symmetric, bit for bit, when
    /// `h` is as [`Self::density_hessian`] returns it.
    fn blocks(el: &Element, h: &Blocks2, scale: f64) -> [[Mat3; 3]; 3] {
        let [g1, g2] = el.grad;
        let k = scale * el.area;
        // q(i, j) = k Σ_ab g_ia g_jb h_ab for particles i, j ∈ {1, 2}
        let q = |gi: [f64; 2], gj: [f64; 2]| {
            (k * gi[0] * gj[0]) * h[0][0]
                + (k * gi[0] * gj[1]) * h[0][1]
                + (k * gi[1] * gj[0]) * h[1][0]
                + (k * gi[1] * gj[1]) * h[1][1]
        };
        let sym = |gi: [f64; 2]| {
            (k * gi[0] * gi[0]) * h[0][0]
                + (k * gi[0] * gi[1]) * (h[0][1] + h[1][0])
                + (k * gi[1] * gi[1]) * h[1][1]
        };
        let q11 = sym(g1);
        let q22 = sym(g2);
        let q12 = q(g1, g2);
        let q21 = q12.transpose();
        let q00 = q11 + (q12 + q21) + q22;
        let q01 = -(q11 + q21);
        let q02 = -(q12 + q22);
        [
            [q00, q01, q02],
            [q01.transpose(), q11, q12],
            [q02.transpose(), q21, q22],
        ]
    }

    /// Everything of triangle `s` at `(x, v)`: strain, and (when asked for) the projected
    /// `∂²W/∂F²`.
    #[inline]
    fn eval(&self, s: usize, x: &[Vec3], hessian: bool) -> (Strain, Option<Blocks2>) {
        let st = self.strain(&self.elements[s], x);
        (st, hessian.then(|| self.projected_hessian(&st)))
    }

    /// The force on triangle `s`: `-A Gᵀ (P + α h Ḟ)` with `P = F S` (`h` needed when
    /// `α ≠ 0`).
    #[inline]
    fn force_of(&self, s: usize, st: &Strain, h: Option<&Blocks2>, v: &[Vec3]) -> [Vec3; 3] {
        let el = &self.elements[s];
        let [f1, f2] = st.f;
        let [s11, s12, s22] = st.s;
        let mut p = [s11 * f1 + s12 * f2, s12 * f1 + s22 * f2];
        if let Some(h) = h.filter(|_| self.damping != 0.0) {
            let d = apply(h, columns(el, v));
            p = [p[0] + self.damping * d[0], p[1] + self.damping * d[1]];
        }
        spread(el, p, -el.area)
    }

    /// `-(a + b α) A Gᵀ h G w` on triangle `s`.
    #[inline]
    fn product_of(&self, s: usize, h: &Blocks2, a: f64, b: f64, w: &[Vec3]) -> [Vec3; 3] {
        let el = &self.elements[s];
        spread(
            el,
            apply(h, columns(el, w)),
            -(a + b * self.damping) * el.area,
        )
    }

    /// The exact energy Hessian blocks of triangle `s` at `x` (unprojected).
    #[cfg(test)]
    fn exact_hessian(&self, s: usize, x: &[Vec3]) -> [[Mat3; 3]; 3] {
        let el = &self.elements[s];
        Self::blocks(el, &self.density_hessian(&self.strain(el, x)), 1.0)
    }
}

/// The precomputed triangle `tri` with rest coordinates `r`.
fn element(tri: [u32; 3], r: &[[f64; 2]; 3]) -> Element {
    let d1 = [r[1][0] - r[0][0], r[1][1] - r[0][1]];
    let d2 = [r[2][0] - r[0][0], r[2][1] - r[0][1]];
    let det = d1[0] * d2[1] - d2[0] * d1[1];
    let size = (d1[0] * d1[0] + d1[1] * d1[1]).max(d2[0] * d2[0] + d2[1] * d2[1]);
    if !(det.abs() > 1e-12 * size) || !det.is_finite() {
        return Element {
            tri,
            grad: [[0.0; 2]; 2],
            area: 0.0,
        };
    }
    // D_m⁻¹ = [[d2y, -d2x], [-d1y, d1x]] / det
    Element {
        tri,
        grad: [[d2[1] / det, -d2[0] / det], [-d1[1] / det, d1[0] / det]],
        area: 0.5 * det.abs(),
    }
}

/// `[Σ_i g_i1 w_i, Σ_i g_i2 w_i]` over the triangle's particles: `F`'s columns for `w = x`,
/// `Ḟ`'s for `w = v`.
#[inline]
fn columns(el: &Element, w: &[Vec3]) -> [Vec3; 2] {
    let [i, j, k] = el.tri.map(|p| w[p as usize]);
    let (d1, d2) = (j - i, k - i);
    let [g1, g2] = el.grad;
    [d1 * g1[0] + d2 * g2[0], d1 * g1[1] + d2 * g2[1]]
}

/// `scale · Gᵀ p`: the vectors on the particles whose pairing with `Ẋ` is `p : Ḟ`.
#[inline]
fn spread(el: &Element, p: [Vec3; 2], scale: f64) -> [Vec3; 3] {
    let [g1, g2] = el.grad;
    let y1 = scale * (g1[0] * p[0] + g1[1] * p[1]);
    let y2 = scale * (g2[0] * p[0] + g2[1] * p[1]);
    [-(y1 + y2), y1, y2]
}

/// `h y` for a 6×6 `h` in blocks.
#[inline]
fn apply(h: &Blocks2, y: [Vec3; 2]) -> [Vec3; 2] {
    [
        h[0][0] * y[0] + h[0][1] * y[1],
        h[1][0] * y[0] + h[1][1] * y[1],
    ]
}

/// Each particle and block takes the triangles' terms one by one (the default
/// [`super::stencil::Accumulate::Each`]).
impl StencilForce for Membrane {
    type Shape = Full<3>;
    const NAME: &'static str = "membrane";
    fn gather(&self) -> &Gather<Full<3>> {
        &self.sums
    }
    fn count(&self) -> usize {
        self.elements.len()
    }
    fn particles(&self, s: usize) -> [u32; 3] {
        self.elements[s].tri
    }
    fn local_energy(&self, s: usize, _t: f64, x: &[Vec3]) -> f64 {
        let el = &self.elements[s];
        self.energy_of(el, &self.strain(el, x))
    }
    /// `½ α A Ḟᵀ h⁺ Ḟ`.
    fn local_dissipation(&self, s: usize, at: &State) -> f64 {
        if self.damping == 0.0 {
            return 0.0;
        }
        let el = &self.elements[s];
        let (_, h) = self.eval(s, at.x, true);
        let fdot = columns(el, at.v);
        let hf = apply(&h.expect("asked for"), fdot);
        0.5 * self.damping * el.area * (fdot[0].dot(hf[0]) + fdot[1].dot(hf[1]))
    }
    fn local_force(&self, s: usize, at: &State) -> [Vec3; 3] {
        let (st, h) = self.eval(s, at.x, self.damping != 0.0);
        self.force_of(s, &st, h.as_ref(), at.v)
    }
    fn has_jacobian(&self, a: f64, b: f64) -> bool {
        a != 0.0 || (b != 0.0 && self.damping != 0.0)
    }
    /// `-(a + b α) H⁺` (no `∂/∂x` of the damping force).
    fn local_jacobian(&self, s: usize, at: &State, a: f64, b: f64) -> [[Mat3; 3]; 3] {
        let (_, h) = self.eval(s, at.x, true);
        let c = -(a + b * self.damping);
        Self::blocks(&self.elements[s], &h.expect("asked for"), c)
    }
    fn local_product(&self, s: usize, at: &State, a: f64, b: f64, w: &[Vec3]) -> [Vec3; 3] {
        let (_, h) = self.eval(s, at.x, true);
        self.product_of(s, &h.expect("asked for"), a, b, w)
    }
    /// One strain and one projected Hessian per triangle for the force, product and matrix.
    fn local(&self, s: usize, at: &Linearization, product: bool, matrix: bool) -> Local<Full<3>> {
        let need = product || matrix || self.damping != 0.0;
        let (st, h) = self.eval(s, at.x, need);
        let ((am, bm), (ap, bp)) = (at.matrix, at.product);
        let zero = [Vec3::ZERO; 3];
        Local {
            force: self.force_of(s, &st, h.as_ref(), at.v),
            product: match (&h, product) {
                (Some(h), true) => self.product_of(s, h, ap, bp, at.w),
                _ => zero,
            },
            matrix: match (&h, matrix) {
                (Some(h), true) => Self::blocks(&self.elements[s], h, -(am + bm * self.damping)),
                _ => [[Mat3::ZERO; 3]; 3],
            },
        }
    }
}

/// Below this `|sin|` of the angle between the global x axis and a triangle's normal, x has no
/// usable projection into the triangle's plane.
const MIN_PROJECTION: f64 = 1e-6;

/// Per-triangle rest coordinates in the material frame: an orthonormal in-plane frame of the
/// rest triangle whose first axis is the warp direction = the 3-D direction in which the
/// texture coordinate u increases (from the triangle's uv gradient) when `uv` is given and
/// non-degenerate on that triangle, else the global x axis projected into the triangle's
/// plane, else (x along the normal) the first edge's direction. Second axis = normal × first.
///
/// The direction "in which u increases" is `∂x/∂u`, the image of the uv plane's u axis (with
/// v held fixed): a thread along the pattern's u axis lies along it. It is the direction of
/// the gradient of u when the uv map is conformal on the triangle. `uv` is per vertex, like
/// `rest`. The coordinates are relative to the triangle's first vertex. A rest triangle of
/// zero area gets its edges' projections onto its first non-zero edge (second coordinate 0).
pub fn material_coordinates(
    rest: &[Vec3],
    triangles: &[[u32; 3]],
    uv: Option<&[[f64; 2]]>,
) -> Vec<[[f64; 2]; 3]> {
    triangles
        .iter()
        .map(|&t| {
            let p = t.map(|i| rest[i as usize]);
            let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
            let cross = e1.cross(e2);
            let size = e1.length_squared().max(e2.length_squared());
            let Some(n) = cross
                .try_normalize()
                .filter(|_| cross.length() > 1e-12 * size)
            else {
                let axis = e1.try_normalize().or(e2.try_normalize()).unwrap_or(Vec3::X);
                return [[0.0; 2], [e1.dot(axis), 0.0], [e2.dot(axis), 0.0]];
            };
            let axis = uv
                .and_then(|uv| {
                    let q = [
                        uv.get(t[0] as usize)?,
                        uv.get(t[1] as usize)?,
                        uv.get(t[2] as usize)?,
                    ];
                    warp_from_uv(e1, e2, q)
                })
                .or_else(|| {
                    let x = Vec3::X - n * n.x;
                    (x.length() > MIN_PROJECTION).then(|| x.normalize())
                })
                .unwrap_or_else(|| e1.normalize());
            let second = n.cross(axis);
            [
                [0.0; 2],
                [e1.dot(axis), e1.dot(second)],
                [e2.dot(axis), e2.dot(second)],
            ]
        })
        .collect()
}

/// `∂x/∂u` normalized, on a triangle with edges `e1 = x_1 - x_0`, `e2 = x_2 - x_0` and texture
/// coordinates `q`: from `e_k = Δu_k ∂x/∂u + Δv_k ∂x/∂v`, `∂x/∂u = (Δv_2 e1 - Δv_1 e2) / det`,
/// `det = Δu_1 Δv_2 - Δu_2 Δv_1`. `None` when the uv triangle is degenerate.
fn warp_from_uv(e1: Vec3, e2: Vec3, q: [&[f64; 2]; 3]) -> Option<Vec3> {
    let (du1, dv1) = (q[1][0] - q[0][0], q[1][1] - q[0][1]);
    let (du2, dv2) = (q[2][0] - q[0][0], q[2][1] - q[0][1]);
    let det = du1 * dv2 - du2 * dv1;
    let size = (du1 * du1 + dv1 * dv1).max(du2 * du2 + dv2 * dv2);
    if !(det.abs() > 1e-12 * size) || !det.is_finite() {
        return None;
    }
    ((dv2 * e1 - dv1 * e2) * det.signum()).try_normalize()
}

#[cfg(test)]
mod tests {
    use super::super::Force;
    use super::super::testing::*;
    use super::*;
    use crate::linalg::eigen::symmetric_eigen;
    use crate::mesh::Mesh;
    use glam::DQuat;
    use proptest::prelude::*;

    fn vec3(r: f64) -> impl Strategy<Value = Vec3> {
        (-r..r, -r..r, -r..r).prop_map(|(a, b, c)| Vec3::new(a, b, c))
    }

    /// Stable orthotropic laws: `Y2 / Y1` from 0.2 to 4 and `ν < 0.45` keep `ν12 ν21 < 0.82`.
    fn law() -> impl Strategy<Value = MembraneLaw> {
        (10.0..1000.0f64, 0.2..4.0f64, 0.0..0.45f64, 5.0..500.0f64).prop_map(|(y1, r, nu, g)| {
            MembraneLaw {
                stretch_modulus: [y1, r * y1],
                poisson: nu,
                shear_modulus: g,
            }
        })
    }

    fn rotation() -> impl Strategy<Value = DQuat> {
        (vec3(1.0), 0.0..6.3f64).prop_filter_map("axis", |(a, t)| {
            a.try_normalize().map(|a| DQuat::from_axis_angle(a, t))
        })
    }

    /// Twice the area over the longest edge squared: 0 for a sliver, √3/2 for equilateral.
    fn quality(p: [Vec3; 3]) -> f64 {
        let l = [p[1] - p[0], p[2] - p[1], p[0] - p[2]].map(|e| e.length_squared());
        (p[1] - p[0]).cross(p[2] - p[0]).length() / l[0].max(l[1]).max(l[2])
    }

    const TRIS: [[u32; 3]; 2] = [[0, 1, 2], [0, 2, 3]];

    /// Two triangles sharing an edge, rest shapes from random 3-D positions (frames from the x
    /// axis), deformed positions that stretch, compress, shear and invert them, velocities.
    fn config() -> impl Strategy<Value = (Membrane, Vec<Vec3>, Vec<Vec3>)> {
        (
            prop::collection::vec(vec3(1.0), 4),
            0.3..1.6f64,
            prop::collection::vec(vec3(0.6), 4),
            prop::collection::vec(vec3(2.0), 4),
            law(),
            0.0..0.05f64,
        )
            .prop_filter_map("well-shaped rest triangles", |(p, s, d, v, law, alpha)| {
                if TRIS.iter().any(|t| quality(t.map(|i| p[i as usize])) < 0.2) {
                    return None;
                }
                let rest = material_coordinates(&p, &TRIS, None);
                let m = Membrane::new(TRIS.to_vec(), rest, law, alpha);
                let x = p.iter().zip(&d).map(|(p, d)| s * *p + *d).collect();
                Some((m, x, v))
            })
    }

    /// Two triangles as in [`config`], deformed by a random stretch `q diag(l1, l2, l3)` with
    /// `l` from 0.1 to 1.5 (so most triangles have a principal stretch under
    /// [`COMPRESSION_STRETCH`], many under 1/√3), plus small displacements.
    fn compressed_config() -> impl Strategy<Value = (Membrane, Vec<Vec3>, Vec<Vec3>)> {
        (
            prop::collection::vec(vec3(1.0), 4),
            (rotation(), 0.1..1.5f64, 0.1..1.5f64, 0.1..1.5f64),
            prop::collection::vec(vec3(0.01), 4),
            prop::collection::vec(vec3(2.0), 4),
            law(),
            0.0..0.05f64,
        )
            .prop_filter_map(
                "well-shaped rest triangles",
                |(p, (q, l1, l2, l3), d, v, law, alpha)| {
                    if TRIS.iter().any(|t| quality(t.map(|i| p[i as usize])) < 0.2) {
                        return None;
                    }
                    let rest = material_coordinates(&p, &TRIS, None);
                    let m = Membrane::new(TRIS.to_vec(), rest, law, alpha);
                    let a = Mat3::from_quat(q)
                        * Mat3::from_diagonal(Vec3::new(l1, l2, l3))
                        * Mat3::from_quat(q.inverse());
                    let x = p.iter().zip(&d).map(|(p, d)| a * *p + *d).collect();
                    Some((m, x, v))
                },
            )
    }

    /// Either kind of configuration, half and half.
    fn any_config() -> impl Strategy<Value = (Membrane, Vec<Vec3>, Vec<Vec3>)> {
        prop_oneof![config(), compressed_config()]
    }

    /// The exact energy Hessian of all triangles, dense.
    fn exact_dense(m: &Membrane, x: &[Vec3]) -> Vec<Vec<f64>> {
        let n = x.len();
        let mut h = vec![vec![0.0; 3 * n]; 3 * n];
        for s in 0..m.count() {
            let blocks = m.exact_hessian(s, x);
            let tri = m.particles(s);
            for (a, &pa) in tri.iter().enumerate() {
                for (b, &pb) in tri.iter().enumerate() {
                    for r in 0..3 {
                        for c in 0..3 {
                            h[3 * pa as usize + r][3 * pb as usize + c] += blocks[a][b].col(c)[r];
                        }
                    }
                }
            }
        }
        h
    }

    fn array12(d: &[Vec<f64>]) -> [[f64; 12]; 12] {
        std::array::from_fn(|i| std::array::from_fn(|j| d[i][j]))
    }

    fn max_abs_entry(d: &[Vec<f64>]) -> f64 {
        d.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()))
    }

    fn forces(m: &Membrane, x: &[Vec3], v: &[Vec3]) -> Vec<Vec3> {
        let mut f = vec![Vec3::ZERO; x.len()];
        m.add_force(&at(x, v), &mut f);
        f
    }

    proptest! {
        #[test]
        fn membrane_force_is_minus_the_energy_gradient((m, x, _v) in any_config()) {
            let zero = vec![Vec3::ZERO; 4];
            let f = forces(&m, &x, &zero);
            let fd = fd_gradient(&m, &x);
            let scale = f.iter().fold(1.0f64, |s, v| s.max(v.length()));
            for i in 0..4 {
                prop_assert!((f[i] - fd[i]).length() < 1e-6 * scale, "{:?} vs {:?}", f[i], fd[i]);
            }
        }

        #[test]
        fn membrane_exact_hessian_is_the_difference_of_the_force((m, x, _v) in any_config()) {
            let zero = vec![Vec3::ZERO; 4];
            let exact = exact_dense(&m, &x);
            let fd: Vec<Vec<f64>> = fd_jacobian(&m, &x, &zero, false)
                .into_iter()
                .map(|row| row.into_iter().map(|k| -k).collect())
                .collect();
            prop_assert!(rel_diff(&exact, &fd) < 1e-6, "rel diff {}", rel_diff(&exact, &fd));
        }

        /// The matrix is symmetric (to the bit) and `-K` positive semi-definite; each
        /// triangle's exact Hessian is positive semi-definite iff its `S` is (§20), and where
        /// every `S` is, the matrix is `-H`.
        #[test]
        fn membrane_matrix_is_the_psd_projection((m, x, v) in any_config()) {
            let k = assembled(&m, &x, &v, 1.0, 0.0);
            let scale = max_abs_entry(&k).max(1e-300);
            for r in 0..12 {
                for c in 0..12 {
                    prop_assert!(k[r][c].to_bits() == k[c][r].to_bits(), "not symmetric: {} {}", k[r][c], k[c][r]);
                }
            }
            let minus_k = array12(&k).map(|row| row.map(|e| -e));
            let (lambda, _) = symmetric_eigen(&minus_k);
            let low = lambda.iter().fold(f64::INFINITY, |a, &b| a.min(b));
            prop_assert!(low >= -1e-10 * scale, "λ_min(-K) = {low}, scale {scale}");
            // per triangle, away from the boundary of the cone, the exact Hessian is PSD
            // iff S is
            let y = m.law().stretch_modulus[0].max(m.law().stretch_modulus[1]);
            let mut tensile = true;
            for (s, el) in m.elements.iter().enumerate() {
                let [a, b, c] = m.strain(el, &x).s;
                let least = 0.5 * (a + c) - (0.25 * (a - c).powi(2) + b * b).sqrt();
                tensile &= least >= 0.0;
                let blocks = m.exact_hessian(s, &x);
                let h: [[f64; 9]; 9] = std::array::from_fn(|i| {
                    std::array::from_fn(|j| blocks[i / 3][j / 3].col(j % 3)[i % 3])
                });
                let (mu, _) = symmetric_eigen(&h);
                let low = mu.iter().fold(f64::INFINITY, |p, &q| p.min(q));
                let big = h.iter().flatten().fold(0.0f64, |p, q| p.max(q.abs()));
                if least.abs() > 1e-4 * y {
                    prop_assert_eq!(least >= 0.0, low >= -1e-10 * big, "λ_min(H) = {}", low);
                }
            }
            let exact = exact_dense(&m, &x);
            if tensile {
                let minus_exact: Vec<Vec<f64>> = exact.iter().map(|r| r.iter().map(|e| -e).collect()).collect();
                prop_assert!(rel_diff(&k, &minus_exact) < 1e-13);
            }
        }

        /// A triangle stretched along both material axes (`F = [λ1 q1, λ2 q2]`, orthonormal
        /// `q`): `S` is diagonal and positive, the exact Hessian is PSD and the matrix is it.
        #[test]
        fn membrane_matrix_of_a_stretched_triangle_is_the_exact_hessian(
            p in prop::collection::vec(vec3(1.0), 3),
            law in law(),
            q in rotation(),
            l1 in 1.0..1.3f64,
            l2 in 1.0..1.3f64,
            c in vec3(2.0),
        ) {
            prop_assume!(quality([p[0], p[1], p[2]]) > 0.2);
            let tri = vec![[0u32, 1, 2]];
            let rest = material_coordinates(&p, &tri, None);
            let m = Membrane::new(tri, rest.clone(), law, 0.0);
            let x: Vec<Vec3> = rest[0]
                .iter()
                .map(|r| c + q * Vec3::new(l1 * r[0], l2 * r[1], 0.0))
                .collect();
            let v = vec![Vec3::ZERO; 3];
            let k = assembled(&m, &x, &v, 1.0, 0.0);
            let exact = exact_dense(&m, &x);
            let h: [[f64; 9]; 9] = std::array::from_fn(|i| std::array::from_fn(|j| exact[i][j]));
            let (mu, _) = symmetric_eigen(&h);
            let scale = max_abs_entry(&exact);
            prop_assert!(mu.iter().all(|&l| l >= -1e-12 * scale), "{mu:?}");
            let minus_exact: Vec<Vec<f64>> = exact.iter().map(|r| r.iter().map(|e| -e).collect()).collect();
            prop_assert!(rel_diff(&k, &minus_exact) == 0.0);
        }

        #[test]
        fn membrane_damping_jacobian_and_dissipation_match_differences((m, x, v) in any_config()) {
            let got = assembled(&m, &x, &v, 0.0, 1.0);
            // the force is linear in v, so a central difference of step 1 m/s is exact up to
            // rounding; a small step would divide the rounding of the (much larger) elastic
            // force by the step
            let fd = fd_jacobian_step(&m, &x, &v, true, 1.0);
            prop_assert!(rel_diff(&got, &fd) < 1e-6, "{}", rel_diff(&got, &fd));
            // -∂Ψ/∂v is the damping part of the force
            let zero = vec![Vec3::ZERO; 4];
            let (f, f0) = (forces(&m, &x, &v), forces(&m, &x, &zero));
            let mut vp = v.clone();
            let scale = f.iter().zip(&f0).fold(1.0f64, |s, (a, b)| s.max((*a - *b).length()));
            for i in 0..4 {
                for d in 0..3 {
                    let e = 1e-6;
                    vp[i][d] = v[i][d] + e;
                    let p = m.dissipation(&at(&x, &vp));
                    vp[i][d] = v[i][d] - e;
                    let q = m.dissipation(&at(&x, &vp));
                    vp[i][d] = v[i][d];
                    let damping = f[i][d] - f0[i][d];
                    prop_assert!((-(p - q) / (2.0 * e) - damping).abs() < 1e-6 * scale);
                }
            }
            // the damping never adds energy
            let power: f64 = f.iter().zip(&f0).zip(&v).map(|((a, b), v)| (*a - *b).dot(*v)).sum();
            prop_assert!(power <= 1e-12 * scale);
        }

        #[test]
        fn membrane_product_and_fused_linearization_agree_with_the_matrix(
            (m, x, v) in any_config(),
            a in -2.0..2.0f64,
            b in -2.0..2.0f64,
            w in prop::collection::vec(vec3(1.0), 4),
        ) {
            prop_assert!(check_product(&m, &x, &v, a, b, &w) < 1e-12);
            let lin = Linearization { t: T, x: &x, v: &v, matrix: (a, b), product: (b, a), w: &w };
            prop_assert!(linearization_is_bitwise_separate(&m, &lin, &w));
            let fused = linearized(&m, &x, &v, a, b);
            prop_assert!(rel_diff(&fused, &assembled(&m, &x, &v, a, b)) == 0.0);
        }

        /// Zero force at rest (in any rigid placement) and an energy invariant under rigid
        /// motions of a deformed patch.
        #[test]
        fn membrane_is_at_rest_in_its_rest_shape_and_frame_invariant(
            (m, x, _v) in config(),
            p in prop::collection::vec(vec3(1.0), 4),
            q in rotation(),
            c in vec3(5.0),
        ) {
            prop_assume!(TRIS.iter().all(|t| quality(t.map(|i| p[i as usize])) > 0.2));
            let zero = vec![Vec3::ZERO; 4];
            let rest = material_coordinates(&p, &TRIS, None);
            let at_rest = Membrane::new(TRIS.to_vec(), rest, m.law(), m.damping());
            let placed: Vec<Vec3> = p.iter().map(|p| q * *p + c).collect();
            let y = m.law().stretch_modulus[0].max(m.law().stretch_modulus[1]);
            for f in forces(&at_rest, &placed, &zero) {
                prop_assert!(f.length() < 1e-12 * y, "{f:?}");
            }
            prop_assert!(at_rest.energy(T, &placed) < 1e-24 * y);
            let moved: Vec<Vec3> = x.iter().map(|x| q * *x + c).collect();
            let (e0, e1) = (m.energy(T, &x), m.energy(T, &moved));
            prop_assert!((e0 - e1).abs() <= 1e-11 * e0.max(1e-300), "{e0} vs {e1}");
        }
    }

    /// A unit square (two triangles) in a tilted plane, warp at angle `phi` in that plane,
    /// given through uv (`phi = None`: no uv, in the xy plane, warp from the x axis); returns
    /// the membrane, rest positions and the warp, weft and normal directions.
    fn square(law: MembraneLaw, phi: Option<f64>) -> (Membrane, Vec<Vec3>, [Vec3; 3]) {
        let (a, b) = match phi {
            Some(_) => {
                let q = DQuat::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), 0.7);
                (q * Vec3::X, q * Vec3::Y)
            }
            None => (Vec3::X, Vec3::Y),
        };
        let n = a.cross(b);
        let o = Vec3::new(0.3, -0.2, 1.1);
        let p: Vec<Vec3> = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
            .iter()
            .map(|s| o + s[0] * a + s[1] * b)
            .collect();
        let t = phi.map_or(a, |phi| phi.cos() * a + phi.sin() * b);
        let w = n.cross(t);
        let uv: Vec<[f64; 2]> = p
            .iter()
            .map(|p| [(*p - o).dot(t), (*p - o).dot(w) + 3.0])
            .collect();
        let rest = material_coordinates(&p, &TRIS, phi.map(|_| &uv[..]));
        (Membrane::new(TRIS.to_vec(), rest, law, 0.0), p, [t, w, n])
    }

    /// `x = o + M (p - o)` with `M = Σ_k c_k d_kᵀ` for the frame `d` and images `c`.
    fn deformed(p: &[Vec3], d: [Vec3; 3], image: [Vec3; 3]) -> Vec<Vec3> {
        p.iter()
            .map(|&q| {
                let r = q - p[0];
                p[0] + (0..3).map(|k| r.dot(d[k]) * image[k]).sum::<Vec3>()
            })
            .collect()
    }

    #[test]
    fn membrane_energy_of_uniform_strains_is_the_analytic_one() {
        let law = MembraneLaw {
            stretch_modulus: [300.0, 120.0],
            poisson: 0.3,
            shear_modulus: 40.0,
        };
        let denom = 1.0 - 0.3 * 0.3 * 120.0 / 300.0;
        let (c11, c22) = (300.0 / denom, 120.0 / denom);
        for phi in [None, Some(0.0), Some(0.4), Some(2.5), Some(-1.2)] {
            let (m, p, [t, w, n]) = square(law, phi);
            for e in [0.05f64, -0.03, 0.2] {
                let l = (1.0 + 2.0 * e).sqrt();
                let warp = deformed(&p, [t, w, n], [l * t, w, n]);
                let weft = deformed(&p, [t, w, n], [t, l * w, n]);
                let (ew, ef) = (m.energy(T, &warp), m.energy(T, &weft));
                assert!(
                    (ew - 0.5 * c11 * e * e).abs() < 1e-12 * c11,
                    "{phi:?} {e}: {ew}"
                );
                assert!(
                    (ef - 0.5 * c22 * e * e).abs() < 1e-12 * c11,
                    "{phi:?} {e}: {ef}"
                );
            }
            // (|γ| ≤ 0.15 keeps the least principal stretch, √(1 − 2|γ|), above s₀ = 0.8)
            for gamma in [0.05f64, -0.1, 0.15] {
                let s = (1.0 - 4.0 * gamma * gamma).sqrt();
                let sheared = deformed(&p, [t, w, n], [t, 2.0 * gamma * t + s * w, n]);
                let es = m.energy(T, &sheared);
                assert!(
                    (es - 2.0 * 40.0 * gamma * gamma).abs() < 1e-12 * c11,
                    "{phi:?}: {es}"
                );
            }
            // ν is the weft contraction under warp stress: at fixed E11 = e the energy is
            // least at E22 = -ν e
            let e = 0.1f64;
            let energy = |e22: f64| {
                let (l1, l2) = ((1.0 + 2.0 * e).sqrt(), (1.0 + 2.0 * e22).sqrt());
                m.energy(T, &deformed(&p, [t, w, n], [l1 * t, l2 * w, n]))
            };
            let best = energy(-0.3 * e);
            assert!(best < energy(-0.3 * e + 1e-3) && best < energy(-0.3 * e - 1e-3));
            assert!(best < energy(0.0) && best < energy(-e));
        }
    }

    /// A square squeezed along the warp (weft held, `F = [s t, w]`): above `s₀` the energy is
    /// St Venant–Kirchhoff's `½ C11 E11²`, whose compressive force `(C11/2) s (1 − s²)` peaks at
    /// `s = 1/√3` and falls to 0 at `s = 0`; below `s₀` it is that energy's second-order
    /// Taylor polynomial at `s₀` (here `C11` is the law's greatest modulus `k`), so the
    /// compressive force keeps growing as the square is squeezed, up to `k s₀³` at `s = 0`.
    #[test]
    fn a_squeezed_square_keeps_its_stiffness() {
        let law = MembraneLaw {
            stretch_modulus: [1000.0, 400.0],
            poisson: 0.2,
            shear_modulus: 100.0,
        };
        let c11 = 1000.0 / (1.0 - 0.2 * 0.2 * 0.4);
        let s0 = COMPRESSION_STRETCH;
        let w = |s: f64| 0.125 * c11 * (s * s - 1.0).powi(2);
        let dw = |s: f64| 0.5 * c11 * s * (s * s - 1.0);
        let ddw = |s: f64| 0.5 * c11 * (3.0 * s * s - 1.0);
        for phi in [None, Some(0.7)] {
            let (m, p, [t, wf, n]) = square(law, phi);
            assert_eq!(m.constants.compression_modulus(), m.constants.c11);
            let zero = vec![Vec3::ZERO; 4];
            let pull =
                |f: &[Vec3]| -> f64 { (0..4).map(|i| (p[i] - p[0]).dot(t) * f[i].dot(t)).sum() };
            let mut last = 0.0;
            for k in 0..40 {
                let s = 1.2 - 0.03 * f64::from(k) - 1e-3;
                let x = deformed(&p, [t, wf, n], [s * t, wf, n]);
                let d = s - s0;
                let (want, want_ds) = if s >= s0 {
                    (w(s), dw(s))
                } else {
                    (
                        w(s0) + dw(s0) * d + 0.5 * ddw(s0) * d * d,
                        dw(s0) + ddw(s0) * d,
                    )
                };
                let e = m.energy(T, &x);
                assert!(
                    (e - want).abs() < 1e-10 * c11,
                    "{phi:?} s = {s}: {e} vs {want}"
                );
                // dW/ds = -Σ_i f_i · ∂x_i/∂s, ∂x_i/∂s = ((p_i - p_0)·t) t
                let f = forces(&m, &x, &zero);
                let tension = -pull(&f);
                assert!(
                    (tension - want_ds).abs() < 1e-9 * c11,
                    "{phi:?} s = {s}: {tension} vs {want_ds}"
                );
                // the compressive force grows as s falls, where St Venant–Kirchhoff's falls
                if s < 1.0 {
                    assert!(
                        -tension > last,
                        "{phi:?} s = {s}: {} after {last}",
                        -tension
                    );
                    last = -tension;
                }
            }
            let stvk = |s: f64| -dw(s);
            assert!(stvk(0.3) < stvk(0.5) && stvk(0.5) < stvk(1.0 / 3f64.sqrt()));
            // at s → 0 the compressive force is k s₀³ (St Venant–Kirchhoff: 0)
            let x = deformed(&p, [t, wf, n], [1e-9 * t, wf, n]);
            let f = forces(&m, &x, &zero);
            let push = pull(&f);
            assert!((push - c11 * s0.powi(3)).abs() < 1e-6 * c11, "{push}");
        }
    }

    #[test]
    fn isotropic_shear_is_the_isotropic_modulus() {
        let g = MembraneLaw::isotropic_shear([500.0, 500.0], 0.25);
        assert!((g - 200.0).abs() < 1e-12);
        // geometric mean of the moduli
        let g = MembraneLaw::isotropic_shear([800.0, 200.0], 0.0);
        assert!((g - 200.0).abs() < 1e-12);
        // with it, an isotropic law gives the same energy to a stretch along any direction
        let law = MembraneLaw {
            stretch_modulus: [500.0, 500.0],
            poisson: 0.25,
            shear_modulus: MembraneLaw::isotropic_shear([500.0, 500.0], 0.25),
        };
        let (m, p, [t, w, n]) = square(law, Some(0.0));
        let e = 0.1f64;
        let l = (1.0 + 2.0 * e).sqrt();
        let along_t = m.energy(T, &deformed(&p, [t, w, n], [l * t, w, n]));
        for theta in [0.3f64, 0.8, 1.9] {
            let d = theta.cos() * t + theta.sin() * w;
            let d2 = n.cross(d);
            let stretched = m.energy(T, &deformed(&p, [d, d2, n], [l * d, d2, n]));
            assert!((stretched - along_t).abs() < 1e-10 * along_t, "{theta}");
        }
    }

    /// A triangle compressed to half its size: `S` is negative definite, the exact Hessian
    /// has negative eigenvalues, the matrix is its projection (positive semi-definite, not
    /// `-H`).
    #[test]
    fn a_compressed_triangle_gets_a_projected_matrix() {
        let law = MembraneLaw {
            stretch_modulus: [200.0, 100.0],
            poisson: 0.2,
            shear_modulus: 30.0,
        };
        let p = [Vec3::ZERO, Vec3::X, Vec3::new(0.3, 0.9, 0.0)];
        let tri = vec![[0u32, 1, 2]];
        let m = Membrane::new(tri.clone(), material_coordinates(&p, &tri, None), law, 0.0);
        let x: Vec<Vec3> = p.iter().map(|p| 0.5 * *p).collect();
        let [a, _, c] = m.strain(&m.elements[0], &x).s;
        assert!(a < 0.0 && c < 0.0);
        let dense = |b: [[Mat3; 3]; 3]| -> [[f64; 9]; 9] {
            std::array::from_fn(|i| std::array::from_fn(|j| b[i / 3][j / 3].col(j % 3)[i % 3]))
        };
        let exact = dense(m.exact_hessian(0, &x));
        let (mu, _) = symmetric_eigen(&exact);
        assert!(mu.iter().any(|&l| l < -1.0), "{mu:?}");
        let v = vec![Vec3::ZERO; 3];
        let minus_k = dense(m.local_jacobian(0, &at(&x, &v), -1.0, 0.0));
        let (lambda, _) = symmetric_eigen(&minus_k);
        assert!(lambda.iter().all(|&l| l > -1e-10), "{lambda:?}");
        let differs = (0..9).any(|i| (0..9).any(|j| (exact[i][j] - minus_k[i][j]).abs() > 1.0));
        assert!(differs);
        // C = I/4: equal principal stretches 0.5 < s₀, the compression term's `2θ` at its
        // limit; the exact Hessian is still the force's difference
        let comp = m.strain(&m.elements[0], &x).compression;
        assert!(comp.is_some_and(|c| c.across.0 > 0.0));
        let fd: Vec<Vec<f64>> = fd_jacobian(&m, &x, &v, false)
            .into_iter()
            .map(|row| row.into_iter().map(|k| -k).collect())
            .collect();
        let exact: Vec<Vec<f64>> = exact.iter().map(|r| r.to_vec()).collect();
        assert!(rel_diff(&exact, &fd) < 1e-6, "{}", rel_diff(&exact, &fd));
    }

    fn edge_lengths(r: &[[f64; 2]; 3]) -> [f64; 3] {
        let d = |a: [f64; 2], b: [f64; 2]| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
        [d(r[0], r[1]), d(r[1], r[2]), d(r[2], r[0])]
    }

    proptest! {
        #[test]
        fn material_coordinates_are_an_isometry(
            p in prop::collection::vec(vec3(1.0), 3),
            uv in prop::option::of(prop::collection::vec((-1.0..1.0f64, -1.0..1.0f64), 3)),
        ) {
            prop_assume!(quality([p[0], p[1], p[2]]) > 0.01);
            let uv: Option<Vec<[f64; 2]>> = uv.map(|u| u.into_iter().map(|(a, b)| [a, b]).collect());
            let r = material_coordinates(&p, &[[0, 1, 2]], uv.as_deref())[0];
            let want = [(p[1] - p[0]).length(), (p[2] - p[1]).length(), (p[0] - p[2]).length()];
            for (got, want) in edge_lengths(&r).iter().zip(want) {
                prop_assert!((got - want).abs() < 1e-12 * (1.0 + want));
            }
            let area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length();
            let det = (r[1][0] - r[0][0]) * (r[2][1] - r[0][1]) - (r[2][0] - r[0][0]) * (r[1][1] - r[0][1]);
            // counter-clockwise about the normal: positive orientation
            prop_assert!((0.5 * det - area).abs() < 1e-12 * (1.0 + area), "{det} {area}");
        }

        /// uv a rotated, shifted copy of the positions in the triangle's plane: the warp is
        /// `∂x/∂u`, so the first coordinate is the u difference and the second ± the v one.
        #[test]
        fn material_coordinates_follow_u(
            s in prop::collection::vec((-1.0..1.0f64, -1.0..1.0f64), 3),
            q in rotation(),
            o in vec3(2.0),
            theta in 0.0..6.3f64,
            shift in (-3.0..3.0f64, -3.0..3.0f64),
        ) {
            let p: Vec<Vec3> = s.iter().map(|&(a, b)| o + q * Vec3::new(a, b, 0.0)).collect();
            prop_assume!(quality([p[0], p[1], p[2]]) > 0.05);
            let (c, sn) = (theta.cos(), theta.sin());
            let uv: Vec<[f64; 2]> = s.iter().map(|&(a, b)| [c * a - sn * b + shift.0, sn * a + c * b + shift.1]).collect();
            let r = material_coordinates(&p, &[[0, 1, 2]], Some(&uv))[0];
            for k in 1..3 {
                prop_assert!((r[k][0] - (uv[k][0] - uv[0][0])).abs() < 1e-12);
                prop_assert!((r[k][1].abs() - (uv[k][1] - uv[0][1]).abs()).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn material_coordinates_fall_back_as_documented() {
        // a triangle in a tilted plane: the x axis projected into it
        let q = DQuat::from_axis_angle(Vec3::new(0.3, 1.0, -0.4).normalize(), 0.9);
        let p: Vec<Vec3> = [[0.0, 0.0], [1.0, 0.2], [0.3, 0.8]]
            .iter()
            .map(|s| q * Vec3::new(s[0], s[1], 0.0))
            .collect();
        let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
        let t = (Vec3::X - n * n.x).normalize();
        let plain = material_coordinates(&p, &[[0, 1, 2]], None)[0];
        for k in 1..3 {
            assert!((plain[k][0] - (p[k] - p[0]).dot(t)).abs() < 1e-14);
            assert!((plain[k][1] - (p[k] - p[0]).dot(n.cross(t))).abs() < 1e-14);
        }
        // degenerate uv (all equal, or collinear) or uv missing a vertex: the same fallback
        for uv in [
            vec![[0.5, 0.5]; 3],
            vec![[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]],
            vec![[0.0, 0.0], [1.0, 0.0]],
        ] {
            assert_eq!(material_coordinates(&p, &[[0, 1, 2]], Some(&uv))[0], plain);
        }
        // normal along x: the first edge
        let p = [
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(2.0, 0.6, 0.8),
            Vec3::new(2.0, -1.0, 0.5),
        ];
        let r = material_coordinates(&p, &[[0, 1, 2]], None)[0];
        assert!(
            (r[1][0] - 1.0).abs() < 1e-15 && r[1][1].abs() < 1e-15,
            "{r:?}"
        );
        let e2 = p[2] - p[0];
        assert!((r[2][0] - e2.dot(Vec3::new(0.0, 0.6, 0.8))).abs() < 1e-15);
    }

    proptest! {
        /// A grid under a uniform affine deformation (and velocity): every interior vertex's
        /// forces from its triangles cancel.
        #[test]
        fn membrane_patch_test(
            law in law(),
            mat in prop::collection::vec(vec3(0.5), 3),
            vel in prop::collection::vec(vec3(1.0), 3),
            c in vec3(1.0),
            theta in prop::option::of(0.0..6.3f64),
        ) {
            let mesh = Mesh::grid([2.0, 1.5], [7, 6], Vec3::new(0.1, 0.2, 0.3), Vec3::Z).unwrap();
            let tris = mesh.triangles();
            let uv: Option<Vec<[f64; 2]>> = theta.map(|t| {
                mesh.positions.iter().map(|p| [t.cos() * p.x - t.sin() * p.y, t.sin() * p.x + t.cos() * p.y]).collect()
            });
            let rest = material_coordinates(&mesh.positions, &tris, uv.as_deref());
            let m = Membrane::new(tris, rest, law, 0.02);
            let a = Mat3::from_cols(mat[0], mat[1], mat[2]) + Mat3::IDENTITY;
            let nv = Mat3::from_cols(vel[0], vel[1], vel[2]);
            let x: Vec<Vec3> = mesh.positions.iter().map(|p| a * *p + c).collect();
            let v: Vec<Vec3> = mesh.positions.iter().map(|p| nv * *p + c).collect();
            let f = forces(&m, &x, &v);
            let scale = (0..m.count())
                .flat_map(|s| m.local_force(s, &at(&x, &v)))
                .fold(0.0f64, |s, g| s.max(g.length()));
            prop_assert!(scale > 0.0);
            for row in 1..5 {
                for col in 1..6 {
                    let g = f[row * 7 + col];
                    prop_assert!(g.length() < 1e-12 * scale, "vertex ({row}, {col}): {g:?} of {scale}");
                }
            }
        }
    }
}
