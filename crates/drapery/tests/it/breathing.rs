//! The shipped animated obstacle `examples/breathing/` (written by `scripts/make_breathing.py`):
//! 61 OBJ frames at 30 fps of a closed ellipsoid torso (largest semi-axis 0.4 m, centre C
//! 0.4 m above the pivot P) that breathes (scaling `s(t) = 1 + 0.1 sin(2π t / 2 s)` about C)
//! and sways (tilt `0.12 sin(…)` rad about z and yaw `0.2 sin(…)` rad about y, through P, same
//! period). Checked with the library's own OBJ reader.

use drapery::io::obj::read_obj;
use drapery::math::Vec3;
use drapery::mesh::Mesh;
use std::collections::HashMap;
use std::path::PathBuf;

const FRAMES: usize = 61;
const FPS: f64 = 30.0;

fn frames() -> Vec<Mesh> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/breathing");
    (1..=FRAMES)
        .map(|k| {
            let path = dir.join(format!("breathing_{k:04}.obj"));
            read_obj(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        })
        .collect()
}

/// Enclosed volume by the divergence theorem: `Σ a · (b × c) / 6` over the triangles.
fn volume(x: &[Vec3], tris: &[[u32; 3]]) -> f64 {
    tris.iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| x[i as usize]);
            a.dot(b.cross(c))
        })
        .sum::<f64>()
        / 6.0
}

#[test]
fn breathing_sequence_is_a_closed_mesh_breathing_smoothly() {
    let frames = frames();
    let first = &frames[0];
    let tris = first.triangles();
    assert!(
        (1000..=3000).contains(&tris.len()),
        "{} triangles",
        tris.len()
    );
    for (k, m) in frames.iter().enumerate() {
        assert_eq!(m.vertex_count(), first.vertex_count(), "frame {}", k + 1);
        assert_eq!(m.faces, first.faces, "frame {}", k + 1);
        assert!(m.lines.is_empty());
    }
    // closed and consistently wound: every directed edge once, its reverse once
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    for t in &tris {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *directed.entry((a, b)).or_default() += 1;
        }
    }
    for (&(a, b), &n) in &directed {
        assert_eq!(n, 1, "edge {a}-{b} used {n} times in that direction");
        assert_eq!(directed.get(&(b, a)), Some(&1), "edge {a}-{b} has no twin");
    }
    // every vertex used (no stray points inside)
    let mut used = vec![false; first.vertex_count()];
    tris.iter().flatten().for_each(|&i| used[i as usize] = true);
    assert!(used.iter().all(|&u| u));

    // The sway is rigid and the breathing scales lengths by s, so V(t) = V₀ s(t)³ (the
    // polyhedron scales exactly). |ds/dt| ≤ 0.1 × 2π / 2 s, so s changes by at most
    // 0.1π / 30 per frame and V by a factor within (1 ± 0.1π / 30 / 0.9)³.
    let vols: Vec<f64> = frames.iter().map(|m| volume(&m.positions, &tris)).collect();
    assert!(vols.iter().all(|&v| v > 0.0), "outward winding: {vols:?}");
    let ds = 0.1 * std::f64::consts::PI / FPS / 0.9;
    let (lo, hi) = ((1.0 - ds).powi(3), (1.0 + ds).powi(3));
    for k in 1..FRAMES {
        let r = vols[k] / vols[k - 1];
        assert!(r > lo && r < hi, "frames {k}–{}: volume ratio {r}", k + 1);
    }
    // the extremes s = 1.1 (t = 0.5 s) and 0.9 (t = 1.5 s) are frames 16 and 46
    let (vmin, vmax) = vols
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &v| (a.min(v), b.max(v)));
    let want = (1.1f64 / 0.9).powi(3);
    assert!(((vmax / vmin) / want - 1.0).abs() < 1e-6, "{}", vmax / vmin);
    assert_eq!(vols[15], vmax);
    assert_eq!(vols[45], vmin);
    // the ellipsoid's volume 4/3 π 0.3 × 0.4 × 0.2 at s = 1 (t = 0), less the subdivided
    // icosahedron's shortfall (a few per cent)
    let ellipsoid = 4.0 / 3.0 * std::f64::consts::PI * 0.3 * 0.4 * 0.2;
    assert!(
        vols[0] < ellipsoid && vols[0] > 0.95 * ellipsoid,
        "{}",
        vols[0]
    );

    // Vertex speed: |s'| |x₀ - C| + (|tilt'| + |yaw'|) |x - P|
    //   ≤ 0.1π × 0.4 + (0.12π + 0.2π) × (0.4 + 1.1 × 0.4) ≈ 0.970 m/s,
    // so at most 0.0324 m per frame (a chord is no longer than its arc).
    let pi = std::f64::consts::PI;
    let speed = 0.1 * pi * 0.4 + (0.12 + 0.2) * pi * (0.4 + 1.1 * 0.4);
    let mut largest = 0.0f64;
    for k in 1..FRAMES {
        for (a, b) in frames[k - 1].positions.iter().zip(&frames[k].positions) {
            largest = largest.max((*b - *a).length());
        }
    }
    assert!(largest <= speed / FPS, "{largest} m in one frame");
    assert!(largest > 0.01, "it moves: {largest}");
    // one period: the last frame is the first pose again (9 printed decimals)
    for (a, b) in first.positions.iter().zip(&frames[FRAMES - 1].positions) {
        assert!((*a - *b).length() < 1e-8);
    }
}
