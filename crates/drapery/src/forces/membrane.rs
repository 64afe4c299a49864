//! The shell membrane, docs/MATH.md §20: an orthotropic St. Venant–Kirchhoff membrane on
//! triangles, in plane stress, written in each rest triangle's material frame (axis 1 = warp,
//! axis 2 = weft).
//!
//! Per triangle with rest coordinates `r_0, r_1, r_2` (material frame, m): `D_m = [r_1 - r_0,
//! r_2 - r_0]`, `F = [x_1 - x_0, x_2 - x_0] D_m⁻¹` (3×2), `E = ½ (FᵀF - I)`, energy `A W(E)` with
//! `W = ½ (C11 E11² + 2 C12 E11 E22 + C22 E22²) + 2 G E12²`. The force is `-∇(A W)` exactly;
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
    /// `[S11, S12, S22]`.
    s: [f64; 3],
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
        Strain {
            f,
            e: [e11, e12, e22],
            s: [
                c.c11 * e11 + c.c12 * e22,
                2.0 * c.g * e12,
                c.c12 * e11 + c.c22 * e22,
            ],
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
        [[h11, h12], [h12.transpose(), h22]]
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
        el.area * w
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
