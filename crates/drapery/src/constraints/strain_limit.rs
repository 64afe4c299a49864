//! Strain limits (docs/MATH.md §22): no mesh edge of a cloth with a `strain_limit` ends a step
//! longer than `(1 + limit)` times its rest length.
//!
//! [`StrainLimits`] holds the edges of the cloths that have a limit, in the order of the cloths
//! and of their meshes' edges, over a compact numbering of those cloths' particles (so that
//! cloths without a limit cost nothing). [`StrainLimits::project`] moves the two ends of every
//! over-long edge along it, weighted by inverse mass, in Gauss–Seidel sweeps in that fixed order
//! until a sweep finds no edge over its bound: sequential, so the same bits whatever the thread
//! count.

use crate::math::Vec3;
use crate::model::Model;

/// An over-long edge is projected to `(1 - SLACK)` times its bound, so that the rounding of
/// later projections never leaves it a hair over.
pub const SLACK: f64 = 1e-6;

/// Most Gauss–Seidel sweeps of one projection; more means the bounds cannot all be met (pins or
/// handles hold a chain of edges farther apart than its limit allows).
pub const MAX_SWEEPS: usize = 1000;

/// Sweeps that project exactly to the target; the later ones over-relax.
pub const PLAIN_SWEEPS: usize = 20;

/// The over-relaxation factor of the sweeps after [`PLAIN_SWEEPS`]: an edge still over its
/// bound then is shortened `OVER_RELAXATION` times as much as it is over the target. Plain
/// sweeps converge slowly when edges are nearly taut between pins (their gradients nearly
/// orthogonal to the sag that makes them long); by then what is left over is small, so the
/// extra shortening is too.
pub const OVER_RELAXATION: f64 = 1.8;

/// The strain-limited edges of a model.
#[derive(Clone, Debug, Default)]
pub struct StrainLimits {
    /// The particles of the cloths that have a limit (global indices, increasing).
    pub particles: Vec<u32>,
    /// Edge ends, as indices into `particles`.
    pub edges: Vec<[u32; 2]>,
    /// Each edge's bound: `(1 + limit)` times its rest length, m.
    pub longest: Vec<f64>,
}

/// What one projection did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Projection {
    /// Sweeps over the edges (the last one found no edge over its bound, unless the cap was hit).
    pub sweeps: usize,
    /// Edges moved, counted once per projection.
    pub projections: usize,
    /// Edges still over their bound when the sweep cap was hit (0 otherwise). Edges whose two
    /// ends cannot move are not counted.
    pub over: usize,
}

impl StrainLimits {
    /// The mesh edges (sides of faces, line elements) of every cloth of `model` that has a
    /// strain limit, with bounds from the rest mesh's edge lengths.
    pub fn of(model: &Model) -> StrainLimits {
        let mut s = StrainLimits::default();
        for (c, limit) in model.cloths().iter().zip(model.strain_limits()) {
            let Some(limit) = *limit else { continue };
            let local = s.particles.len() as u32;
            s.particles.extend(c.range().map(|p| p as u32));
            let rest = &c.mesh.positions;
            for [a, b] in c.mesh.edges() {
                let length = (rest[a as usize] - rest[b as usize]).length();
                s.edges.push([a + local, b + local]);
                s.longest.push((1.0 + limit) * length);
            }
        }
        s
    }

    /// True when no cloth has a limit.
    pub fn is_empty(&self) -> bool {
        self.edges.is_empty()
    }

    /// Projects positions `x` (indexed as [`StrainLimits::particles`]) with inverse masses `w`
    /// (0 for a particle that must not move) until no edge is over its bound, or for at most
    /// `max_sweeps` sweeps. Each projection moves the ends of an edge of length `L` over its
    /// bound `B` by `∓ wᵢ / (w_a + w_b) · (L - (1 - SLACK) B) · d̂`, so `Σ mᵢ Δxᵢ = 0` when both
    /// can move.
    pub fn project(&self, x: &mut [Vec3], w: &[f64], max_sweeps: usize) -> Projection {
        let mut out = Projection::default();
        while out.sweeps < max_sweeps {
            let omega = match out.sweeps < PLAIN_SWEEPS {
                true => 1.0,
                false => OVER_RELAXATION,
            };
            out.sweeps += 1;
            let mut moved = 0;
            for (e, &[a, b]) in self.edges.iter().enumerate() {
                let (a, b) = (a as usize, b as usize);
                let (wa, wb) = (w[a], w[b]);
                let d = x[b] - x[a];
                let length = d.length();
                if !(length > self.longest[e]) || wa + wb == 0.0 {
                    continue;
                }
                let target = self.longest[e] * (1.0 - SLACK);
                let c = d * (omega * (length - target) / (length * (wa + wb)));
                x[a] += wa * c;
                x[b] -= wb * c;
                moved += 1;
            }
            out.projections += moved;
            if moved == 0 {
                return out;
            }
        }
        out.over = self.over(x, w);
        out
    }

    /// Edges over their bound at `x` whose ends are not both fixed (`w = 0`).
    pub fn over(&self, x: &[Vec3], w: &[f64]) -> usize {
        (self.edges.iter().zip(&self.longest))
            .filter(|&(&[a, b], &longest)| {
                let (a, b) = (a as usize, b as usize);
                w[a] + w[b] > 0.0 && (x[b] - x[a]).length() > longest
            })
            .count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chain(n: usize, longest: f64) -> StrainLimits {
        StrainLimits {
            particles: (0..n as u32).collect(),
            edges: (0..n as u32 - 1).map(|k| [k, k + 1]).collect(),
            longest: vec![longest; n - 1],
        }
    }

    #[test]
    fn one_edge_moves_its_ends_by_inverse_mass_and_keeps_the_centre_of_mass() {
        let s = chain(2, 1.1);
        let mut x = vec![Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0)];
        // masses 1 and 3
        let w = [1.0, 1.0 / 3.0];
        let p = s.project(&mut x, &w, MAX_SWEEPS);
        assert_eq!((p.sweeps, p.projections, p.over), (2, 1, 0));
        let length = (x[1] - x[0]).length();
        assert!((length - 1.1 * (1.0 - SLACK)).abs() < 1e-15, "{length}");
        // the centre of mass (1·x₀ + 3·x₁)/4 = 1.5 stays; the light end moves 3 times as far
        assert!(((x[0].x + 3.0 * x[1].x) / 4.0 - 1.5).abs() < 1e-15);
        assert!((x[0].x - 3.0 * (2.0 - x[1].x)).abs() < 1e-15);
        assert_eq!((x[0].y, x[1].z), (0.0, 0.0));
    }

    #[test]
    fn a_chain_from_a_fixed_end_comes_within_its_bounds() {
        let s = chain(6, 0.5);
        let mut x: Vec<Vec3> = (0..6)
            .map(|k| Vec3::new(0.0, -(k * k) as f64, 0.0))
            .collect();
        let mut w = vec![1.0; 6];
        w[0] = 0.0;
        let p = s.project(&mut x, &w, MAX_SWEEPS);
        assert_eq!((p.over, x[0]), (0, Vec3::ZERO));
        assert!(p.sweeps < MAX_SWEEPS);
        for k in 0..5 {
            assert!((x[k + 1] - x[k]).length() <= 0.5, "edge {k}");
        }
    }

    #[test]
    fn an_infeasible_chain_stops_at_the_cap_and_counts_what_is_over() {
        // both ends fixed 5 m apart, 4 edges that may be 1 m long at most
        let s = chain(5, 1.0);
        let mut x: Vec<Vec3> = (0..5)
            .map(|k| Vec3::new(1.25 * k as f64, 0.0, 0.0))
            .collect();
        let w = [0.0, 1.0, 1.0, 1.0, 0.0];
        let p = s.project(&mut x, &w, 50);
        assert_eq!(p.sweeps, 50);
        assert!(p.over > 0 && p.over <= 4, "{p:?}");
        assert_eq!(p.over, s.over(&x, &w));
        assert_eq!((x[0], x[4]), (Vec3::ZERO, Vec3::new(5.0, 0.0, 0.0)));
        // an edge whose ends are both fixed is neither moved nor counted
        let s = chain(2, 1.0);
        let mut x = vec![Vec3::ZERO, Vec3::new(3.0, 0.0, 0.0)];
        let p = s.project(&mut x, &[0.0, 0.0], 10);
        assert_eq!((p.sweeps, p.over, x[1].x), (1, 0, 3.0));
    }

    #[test]
    fn a_sheet_sagging_between_two_pinned_corners_comes_within_its_bounds_in_few_sweeps() {
        use crate::mesh::Mesh;
        use crate::model::{ClothDesc, MassSpec, Material};
        // 11 × 11 vertices 0.1 m apart, the top corners pinned: the top row is nearly taut
        // between them (2 % to spare), where plain Gauss–Seidel sweeps crawl
        let k = 11;
        let cloth = ClothDesc {
            name: "s".into(),
            mesh: Mesh::grid([1.0, 1.0], [k, k], Vec3::ZERO, Vec3::Z).unwrap(),
            material: Material {
                mass: MassSpec::PerVertex(0.01),
                strain_limit: Some(0.02),
                ..Material::default()
            },
            pins: vec![0, k as u32 - 1],
            initial_velocity: Vec3::ZERO,
            handles: Vec::new(),
        };
        let m = Model::new(vec![cloth], Vec3::ZERO).unwrap();
        let s = StrainLimits::of(&m);
        assert_eq!(s.edges.len(), 2 * k * (k - 1));
        let w: Vec<f64> = m
            .pins()
            .iter()
            .map(|&p| if p { 0.0 } else { 1.0 })
            .collect();
        // every free vertex sags 3 cm and more further down, with some noise
        let mut x: Vec<Vec3> = (m.positions().iter().enumerate())
            .map(|(i, p)| {
                let f = i as f64;
                let sag = Vec3::new(
                    0.003 * (1.3 * f).sin(),
                    -0.03 - 0.003 * (i / k) as f64,
                    0.01 * (0.7 * f).cos(),
                );
                *p + w[i] * sag
            })
            .collect();
        assert!(s.over(&x, &w) > 100);
        let p = s.project(&mut x, &w, MAX_SWEEPS);
        assert_eq!(p.over, 0);
        assert!(p.sweeps < 100, "{p:?}");
        assert_eq!(s.over(&x, &w), 0);
        assert_eq!((x[0], x[k - 1]), (m.positions()[0], m.positions()[k - 1]));
    }
}
