//! Exact orientation predicates for the intersection checker.
//!
//! [`orient3d`] and [`orient2d`] return the *exact* sign of the orientation determinant of
//! finite `f64` points (provided no intermediate product overflows or underflows): a fast
//! floating-point evaluation is used when a forward error bound proves its sign, otherwise the
//! determinant is recomputed exactly as a sum of `f64` terms (exact products via fused
//! multiply-add, exact sums via non-overlapping expansions, after Shewchuk's "Adaptive Precision
//! Floating-Point Arithmetic").
//!
//! On a flat sheet every pair of neighbouring triangles is coplanar, so every test takes the
//! exact path: a run's first step checks the starting mesh for tangles, and spent 7 of its 11 s
//! there at 290² vertices. When the coordinate differences are themselves exact (nearby
//! vertices, Sterbenz), the determinant is summed from 24 terms instead of 192 (4 instead of 16
//! in 2D), a column of zero differences (points in a plane, or on a line, normal to an axis)
//! gives 0 at once, and the terms stay on the stack.

use crate::math::Vec3;

/// `a + b = s + e` exactly.
#[inline]
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    let e = (a - (s - bb)) + (b - bb);
    (s, e)
}

/// `a × b = p + e` exactly (fused multiply-add gives the rounding error).
#[inline]
fn two_product(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    (p, a.mul_add(b, -p))
}

/// Up to `N` exact terms, on the stack (the predicates run millions of times on a flat sheet,
/// where every neighbouring pair is coplanar and takes the exact path). [`orient3d`]'s general
/// case needs the most: six products of three two-term factors, 32 terms each.
struct Terms<const N: usize> {
    t: [f64; N],
    len: usize,
}

impl<const N: usize> Terms<N> {
    fn new() -> Self {
        Terms {
            t: [0.0; N],
            len: 0,
        }
    }

    fn push(&mut self, x: f64) {
        self.t[self.len] = x;
        self.len += 1;
    }

    /// Sign (-1, 0, 1) of the exact sum of the terms: each is added to a non-overlapping
    /// expansion of increasing magnitude (Shewchuk's GROW-EXPANSION, zero components dropped),
    /// whose largest component then carries the sign.
    fn sign(&self) -> i32 {
        let mut e = [0.0; N];
        let mut len = 0;
        for &b in &self.t[..self.len] {
            let mut q = b;
            let mut k = 0;
            for i in 0..len {
                let (s, err) = two_sum(q, e[i]);
                q = s;
                if err != 0.0 {
                    e[k] = err;
                    k += 1;
                }
            }
            if q != 0.0 {
                e[k] = q;
                k += 1;
            }
            len = k;
        }
        match e[..len].last() {
            Some(&v) if v > 0.0 => 1,
            Some(&v) if v < 0.0 => -1,
            _ => 0,
        }
    }

    /// Pushes the exact terms of `sign × u × v × w` (each factor a two-term sum).
    fn push_product(&mut self, sign: f64, u: [f64; 2], v: [f64; 2], w: [f64; 2]) {
        for ui in u {
            for vj in v {
                let (p, e) = two_product(ui, vj);
                for x in [p, e] {
                    for wk in w {
                        let (q, f) = two_product(x, wk);
                        self.push(sign * q);
                        self.push(sign * f);
                    }
                }
            }
        }
    }

    /// Pushes the exact terms of `sign × u × v` for two-term factors (8 terms).
    fn push_product2(&mut self, sign: f64, u: [f64; 2], v: [f64; 2]) {
        for ui in u {
            for vj in v {
                let (p, e) = two_product(ui, vj);
                self.push(sign * p);
                self.push(sign * e);
            }
        }
    }

    /// Pushes the exact terms of `sign × u × v × w` for single numbers (4 terms).
    fn push_product1(&mut self, sign: f64, u: f64, v: f64, w: f64) {
        let (p, e) = two_product(u, v);
        for x in [p, e] {
            let (q, f) = two_product(x, w);
            self.push(sign * q);
            self.push(sign * f);
        }
    }
}

/// `a - b` as an exact two-term sum.
#[inline]
fn diff(a: f64, b: f64) -> [f64; 2] {
    let (s, e) = two_sum(a, -b);
    [s, e]
}

/// Sign of `det[a-d; b-d; c-d]`: positive when `d` lies below the plane through `a, b, c`
/// (seen so that `a, b, c` turn counter-clockwise from above), zero when the four points are
/// coplanar, negative otherwise. Exact for finite input.
pub fn orient3d(a: Vec3, b: Vec3, c: Vec3, d: Vec3) -> i32 {
    let (ad, bd, cd) = (a - d, b - d, c - d);
    let m1 = bd.y * cd.z - bd.z * cd.y;
    let m2 = cd.y * ad.z - cd.z * ad.y;
    let m3 = ad.y * bd.z - ad.z * bd.y;
    let det = ad.x * m1 + bd.x * m2 + cd.x * m3;
    let perm = ad.x.abs() * ((bd.y * cd.z).abs() + (bd.z * cd.y).abs())
        + bd.x.abs() * ((cd.y * ad.z).abs() + (cd.z * ad.y).abs())
        + cd.x.abs() * ((ad.y * bd.z).abs() + (ad.z * bd.y).abs());
    let bound = 16.0 * f64::EPSILON * perm;
    if det > bound {
        return 1;
    }
    if det < -bound {
        return -1;
    }
    if !det.is_finite() {
        return 0;
    }
    let diffs = differences(a, b, c, d);
    if diffs.iter().all(|d| d[1] == 0.0) {
        // the differences are exact (as they are between the nearby points of a mesh): six
        // products of three numbers, 24 terms
        let e = diffs.map(|d| d[0]);
        if (0..3).any(|k| [e[k], e[k + 3], e[k + 6]] == [0.0; 3]) {
            // a zero column: the points lie in a plane normal to an axis
            return 0;
        }
        let mut t = Terms::<24>::new();
        for (sign, u, v, w) in expansion_by_minors(e) {
            t.push_product1(sign, u, v, w);
        }
        return t.sign();
    }
    let mut t = Terms::<192>::new();
    for (sign, u, v, w) in expansion_by_minors(diffs) {
        t.push_product(sign, u, v, w);
    }
    t.sign()
}

/// `[a - d, b - d, c - d]` coordinate by coordinate (`[adx, ady, adz, bdx, ...]`), each as an
/// exact two-term sum.
fn differences(a: Vec3, b: Vec3, c: Vec3, d: Vec3) -> [[f64; 2]; 9] {
    let [a, b, c, d] = [a, b, c, d].map(|p| p.to_array());
    std::array::from_fn(|k| {
        let row = [a, b, c][k / 3];
        diff(row[k % 3], d[k % 3])
    })
}

/// The six signed products of the 3×3 determinant of rows `(a, b, c)`, given as
/// `[ax, ay, az, bx, by, bz, cx, cy, cz]`.
fn expansion_by_minors<F: Copy>(d: [F; 9]) -> [(f64, F, F, F); 6] {
    let [ax, ay, az, bx, by, bz, cx, cy, cz] = d;
    [
        (1.0, ax, by, cz),
        (-1.0, ax, bz, cy),
        (1.0, bx, cy, az),
        (-1.0, bx, cz, ay),
        (1.0, cx, ay, bz),
        (-1.0, cx, az, by),
    ]
}

/// Sign of `det[a-c; b-c]` for 2D points `[x, y]`: positive when `a, b, c` turn
/// counter-clockwise. Exact for finite input.
pub fn orient2d(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> i32 {
    let (acx, acy, bcx, bcy) = (a[0] - c[0], a[1] - c[1], b[0] - c[0], b[1] - c[1]);
    let det = acx * bcy - acy * bcx;
    let bound = 8.0 * f64::EPSILON * ((acx * bcy).abs() + (acy * bcx).abs());
    if det > bound {
        return 1;
    }
    if det < -bound {
        return -1;
    }
    if !det.is_finite() {
        return 0;
    }
    let [acx, acy, bcx, bcy] = [
        diff(a[0], c[0]),
        diff(a[1], c[1]),
        diff(b[0], c[0]),
        diff(b[1], c[1]),
    ];
    let mut t = Terms::<16>::new();
    if [acx, acy, bcx, bcy].iter().all(|d| d[1] == 0.0) {
        // exact differences: a zero column means three points on a line normal to an axis
        if (acx[0] == 0.0 && bcx[0] == 0.0) || (acy[0] == 0.0 && bcy[0] == 0.0) {
            return 0;
        }
        let (p, e) = two_product(acx[0], bcy[0]);
        let (q, f) = two_product(acy[0], bcx[0]);
        for x in [p, e, -q, -f] {
            t.push(x);
        }
        return t.sign();
    }
    t.push_product2(1.0, acx, bcy);
    t.push_product2(-1.0, acy, bcx);
    t.sign()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn orientation_of_simple_configurations() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        assert_eq!(orient3d(a, b, c, -Vec3::Z), 1);
        assert_eq!(orient3d(a, b, c, Vec3::Z), -1);
        assert_eq!(orient3d(a, b, c, Vec3::new(0.3, 0.7, 0.0)), 0);
        assert_eq!(orient2d([0.0, 0.0], [1.0, 0.0], [0.0, 1.0]), 1);
        assert_eq!(orient2d([0.0, 0.0], [1.0, 1.0], [2.0, 2.0]), 0);
        // points on a line or in a plane normal to an axis (a flat sheet), and one just off it
        let y = 0.52;
        assert_eq!(orient2d([0.3, 0.1], [0.3, 0.7], [0.3, 0.2]), 0);
        assert_eq!(orient2d([0.1, y], [0.7, y], [0.2, y]), 0);
        assert_eq!(orient2d([0.1, y], [0.7, y], [0.2, y.next_up()]), 1);
        let (p, q, r) = (
            Vec3::new(0.1, y, 0.3),
            Vec3::new(0.7, y, 0.2),
            Vec3::new(0.4, y, 0.9),
        );
        assert_eq!(orient3d(p, q, r, Vec3::new(-0.3, y, 0.05)), 0);
        let above = orient3d(p, q, r, Vec3::new(-0.3, y.next_up(), 0.05));
        assert_eq!(
            above,
            -orient3d(q, p, r, Vec3::new(-0.3, y.next_up(), 0.05))
        );
        assert_ne!(above, 0);
    }

    #[test]
    fn nearly_degenerate_cases_are_exact() {
        // points on the line y = x, perturbed by one ulp: the naive determinant is unreliable
        let c = [24.0, 24.0];
        let b = [12.0, 12.0];
        for i in 0..64 {
            let x = 0.5 + i as f64 * f64::EPSILON;
            for (dy, want) in [(0.0, 0), (f64::EPSILON, 1), (-f64::EPSILON, -1)] {
                let a = [x, x + dy * x];
                if a[1] == x {
                    assert_eq!(orient2d(a, b, c), 0);
                } else {
                    assert_eq!(orient2d(a, b, c), want, "{a:?}");
                }
            }
        }
        // exactly coplanar points with non-representable combinations
        let p = Vec3::new(0.1, 0.2, 0.3);
        let u = Vec3::new(1.0, 0.0, 0.5);
        let v = Vec3::new(0.0, 1.0, 0.25);
        // d = p + 3u - 2v, computed exactly (small integers times exact binary fractions)
        let d = Vec3::new(0.1 + 3.0, 0.2 - 2.0, 0.3 + 1.5 - 0.5);
        let s = orient3d(p, p + u, p + v, d);
        // sign must agree with the exact determinant of (p, p+u, p+v, d) — check antisymmetry
        assert_eq!(s, -orient3d(p + u, p, p + v, d));
        assert_eq!(s, orient3d(p + u, p + v, p, d));
    }

    /// The integer determinant `det[a-d; b-d; c-d]`, exactly.
    fn integer_det(p: [[i64; 3]; 4]) -> i64 {
        let [a, b, c, d] = p;
        let r = |u: [i64; 3]| [u[0] - d[0], u[1] - d[1], u[2] - d[2]];
        let (u, v, w) = (r(a), r(b), r(c));
        u[0] * (v[1] * w[2] - v[2] * w[1])
            + v[0] * (w[1] * u[2] - w[2] * u[1])
            + w[0] * (u[1] * v[2] - u[2] * v[1])
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]

        /// Points of a lattice (integers times a power of two, moved by an offset that keeps
        /// their differences exact, as a mesh's nearby vertices are): coplanar ones in an oblique
        /// plane, in a plane normal to an axis (a flat sheet) and off the plane by one lattice
        /// step; the sign is the integer determinant's (the exact-difference path), and that of
        /// the general 192-term sum.
        #[test]
        fn orient3d_of_lattice_points_is_the_integer_determinants_sign(
            u in prop::array::uniform3(-9i64..10), v in prop::array::uniform3(-9i64..10),
            ij in prop::array::uniform4(-30i64..30), base in prop::array::uniform3(-500i64..500),
            lift in -1i64..2, axis in 0usize..4, scale in -30i32..-12, offset in 0.5..0.75f64,
        ) {
            let mut u = u;
            let mut v = v;
            if axis < 3 {
                // a plane normal to an axis
                u[axis] = 0;
                v[axis] = 0;
            }
            let point = |k: usize| -> [i64; 3] {
                let (i, j) = (ij[k % 4], ij[(k + 1) % 4] - ij[(k + 2) % 4]);
                let mut p = [0; 3];
                for q in 0..3 {
                    p[q] = base[q] + i * u[q] + j * v[q];
                }
                p
            };
            let mut pts = [point(0), point(1), point(2), point(3)];
            pts[3][(axis + 1) % 3] += lift;
            // |p| < 1100 and h <= 2^-13 keep the coordinates in [0.25, 1): there they are
            // exact (multiples of 2^-54 at least) and so are their differences (Sterbenz)
            let h = 2f64.powi(scale);
            let at = |p: [i64; 3]| Vec3::new(
                offset + p[0] as f64 * h, offset + p[1] as f64 * h, offset + p[2] as f64 * h);
            let [a, b, c, d] = pts.map(at);
            let want = integer_det(pts).signum() as i32;
            prop_assert_eq!(orient3d(a, b, c, d), want);
            // the general 192-term sum
            let mut t = Terms::<192>::new();
            for (sign, u, v, w) in expansion_by_minors(differences(a, b, c, d)) {
                t.push_product(sign, u, v, w);
            }
            prop_assert_eq!(t.sign(), want);
            // orient2d on two of the coordinates
            let (k, l) = ((axis + 1) % 3, (axis + 2) % 3);
            let flat = |p: Vec3| [p.to_array()[k], p.to_array()[l]];
            let [pa, pb, pc] = [pts[0], pts[1], pts[3]];
            let det2 = (pa[k] - pc[k]) * (pb[l] - pc[l]) - (pa[l] - pc[l]) * (pb[k] - pc[k]);
            prop_assert_eq!(orient2d(flat(a), flat(b), flat(d)), det2.signum() as i32);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(1000))]

        #[test]
        fn orient3d_is_antisymmetric_and_agrees_with_clear_cases(
            a in prop::array::uniform3(-1.0..1.0f64),
            b in prop::array::uniform3(-1.0..1.0f64),
            c in prop::array::uniform3(-1.0..1.0f64),
            s in -1.0..1.0f64, t in -1.0..1.0f64, tiny in -1e-15..1e-15f64,
        ) {
            let (a, b, c) = (Vec3::from_array(a), Vec3::from_array(b), Vec3::from_array(c));
            // d almost on the plane of a, b, c
            let n = (b - a).cross(c - a);
            let d = a + (b - a) * s + (c - a) * t + n * tiny;
            let o = orient3d(a, b, c, d);
            prop_assert_eq!(o, -orient3d(b, a, c, d));
            prop_assert_eq!(o, orient3d(b, c, a, d));
            prop_assert_eq!(o, -orient3d(a, b, d, c));
            let far = a + n;
            prop_assert_eq!(orient3d(a, b, c, far), if n.length() > 0.0 { -1 } else { 0 });
        }
    }
}
