//! The shipped animated obstacles, OBJ sequences of closed meshes at 30 fps, read with the
//! library's own OBJ reader:
//!
//! * `examples/breathing/` (`scripts/make_breathing.py`): 61 frames of a closed ellipsoid torso
//!   (largest semi-axis 0.4 m, centre C 0.4 m above the pivot P) that breathes (scaling
//!   `s(t) = 1 + 0.1 sin(2π t / 2 s)` about C) and sways (tilt `0.12 sin(…)` rad about z and yaw
//!   `0.2 sin(…)` rad about y, through P, same period);
//! * `examples/mannequin/` (`scripts/make_mannequin.py`): 61 frames of a surface-nets mannequin
//!   whose arms turn sideways about the shoulders by `65° (1 - cos(2π t / 2 s)) / 2` while the
//!   whole body turns about the vertical axis by `0.5 sin(2π t / 2 s)` rad;
//! * `examples/mannequin_walk/` (the same script): 41 frames at 20 fps of the same body in an
//!   A-pose, walking in place (thighs swinging ±20° about the hips, knees bending up to 45°)
//!   while it turns a quarter turn to its left in 1.6 s.

use drapery::collision::check::count_self_intersections;
use drapery::io::obj::read_obj;
use drapery::math::Vec3;
use drapery::mesh::Mesh;
use std::collections::HashMap;
use std::f64::consts::PI;
use std::path::PathBuf;

const FRAMES: usize = 61;
const FPS: f64 = 30.0;

/// The frames `<stem>_0001.obj` … of `examples/<stem>/` (61 of them), all with the first
/// frame's vertex count and faces (asserted); and the triangles.
fn frames(stem: &str) -> (Vec<Mesh>, Vec<[u32; 3]>) {
    frames_n(stem, FRAMES)
}

/// The `count` frames `<stem>_0001.obj` … of `examples/<stem>/`, as [`frames`] reads them.
fn frames_n(stem: &str, count: usize) -> (Vec<Mesh>, Vec<[u32; 3]>) {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(stem);
    let frames: Vec<Mesh> = (1..=count)
        .map(|k| {
            let path = dir.join(format!("{stem}_{k:04}.obj"));
            read_obj(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        })
        .collect();
    let first = &frames[0];
    for (k, m) in frames.iter().enumerate() {
        assert_eq!(m.vertex_count(), first.vertex_count(), "frame {}", k + 1);
        assert_eq!(m.faces, first.faces, "frame {}", k + 1);
        assert!(m.lines.is_empty());
    }
    let tris = first.triangles();
    (frames, tris)
}

/// Closed and consistently wound: every directed edge once, its reverse once; every vertex
/// used.
fn assert_closed(tris: &[[u32; 3]], vertices: usize) {
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    for t in tris {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *directed.entry((a, b)).or_default() += 1;
        }
    }
    for (&(a, b), &n) in &directed {
        assert_eq!(n, 1, "edge {a}-{b} used {n} times in that direction");
        assert_eq!(directed.get(&(b, a)), Some(&1), "edge {a}-{b} has no twin");
    }
    let mut used = vec![false; vertices];
    tris.iter().flatten().for_each(|&i| used[i as usize] = true);
    assert!(used.iter().all(|&u| u), "stray vertices");
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

/// The largest distance any vertex moves from one frame to the next.
fn largest_move(frames: &[Mesh]) -> f64 {
    let mut largest = 0.0f64;
    for k in 1..frames.len() {
        for (a, b) in frames[k - 1].positions.iter().zip(&frames[k].positions) {
            largest = largest.max((*b - *a).length());
        }
    }
    largest
}

/// Every frame free of self-intersections, the last frame the first pose again (one period;
/// 9 printed decimals).
fn assert_clean_loop(frames: &[Mesh], tris: &[[u32; 3]]) {
    for (k, m) in frames.iter().enumerate() {
        let n = count_self_intersections(&m.positions, tris);
        assert_eq!(n, 0, "frame {}: {n} intersecting triangle pairs", k + 1);
    }
    let (first, last) = (&frames[0], &frames[frames.len() - 1]);
    for (a, b) in first.positions.iter().zip(&last.positions) {
        assert!((*a - *b).length() < 1e-8);
    }
}

/// The frames of `examples/<stem>/` and their triangles, checked: a triangle count in `count`,
/// closed, free of self-intersections, looping.
fn closed_loop(stem: &str, count: std::ops::RangeInclusive<usize>) -> (Vec<Mesh>, Vec<[u32; 3]>) {
    let (frames, tris) = frames(stem);
    assert!(count.contains(&tris.len()), "{}", tris.len());
    assert_closed(&tris, frames[0].vertex_count());
    assert_clean_loop(&frames, &tris);
    (frames, tris)
}

#[test]
fn breathing_sequence_is_a_closed_mesh_breathing_smoothly() {
    let (frames, tris) = closed_loop("breathing", 1000..=3000);

    // The sway is rigid and the breathing scales lengths by s, so V(t) = V₀ s(t)³ (the
    // polyhedron scales exactly). |ds/dt| ≤ 0.1 × 2π / 2 s, so s changes by at most
    // 0.1π / 30 per frame and V by a factor within (1 ± 0.1π / 30 / 0.9)³.
    let vols: Vec<f64> = frames.iter().map(|m| volume(&m.positions, &tris)).collect();
    assert!(vols.iter().all(|&v| v > 0.0), "outward winding: {vols:?}");
    let ds = 0.1 * PI / FPS / 0.9;
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
    let ellipsoid = 4.0 / 3.0 * PI * 0.3 * 0.4 * 0.2;
    assert!(
        vols[0] < ellipsoid && vols[0] > 0.95 * ellipsoid,
        "{}",
        vols[0]
    );

    // Vertex speed: |s'| |x₀ - C| + (|tilt'| + |yaw'|) |x - P|
    //   ≤ 0.1π × 0.4 + (0.12π + 0.2π) × (0.4 + 1.1 × 0.4) ≈ 0.970 m/s,
    // so at most 0.0324 m per frame (a chord is no longer than its arc).
    let speed = 0.1 * PI * 0.4 + (0.12 + 0.2) * PI * (0.4 + 1.1 * 0.4);
    let largest = largest_move(&frames);
    assert!(largest <= speed / FPS, "{largest} m in one frame");
    assert!(largest > 0.01, "it moves: {largest}");
}

#[test]
fn mannequin_sequence_is_a_closed_mesh_raising_its_arms() {
    let (frames, tris) = closed_loop("mannequin", 4000..=6500);
    for (k, m) in frames.iter().enumerate() {
        assert!(volume(&m.positions, &tris) > 0.0, "frame {}", k + 1);
        // standing on the ground, within 0.9 m of the vertical axis it turns about
        for p in &m.positions {
            assert!(p.y > 0.0 && p.x.hypot(p.z) < 0.9, "frame {}: {p}", k + 1);
        }
    }
    // The hands (centre 0.585 m from the shoulder joint at x = ±0.21 m, 13.3° from the
    // vertical, radius 0.045 m) reach |x| ≤ 0.39 m at rest; at t = 1 s (frame 31, no turn)
    // the arms are 65° higher: |x| = 0.21 + 0.585 sin(78.3°) + 0.045 ≈ 0.83 m.
    let reach = |m: &Mesh| m.positions.iter().fold(0.0f64, |r, p| r.max(p.x.abs()));
    assert!(reach(&frames[0]) < 0.4, "{}", reach(&frames[0]));
    assert!(reach(&frames[30]) > 0.8, "{}", reach(&frames[30]));
    // Vertex speed: the turn, |turn'| ≤ 0.5 × π rad/s at ≤ 0.9 m from the axis, plus the arm,
    // |raise'| ≤ 65° × π / 2 s⁻¹ at ≤ 0.63 m from the shoulder: at most 0.085 m per frame.
    let speed = 0.5 * PI * 0.9 + 65f64.to_radians() * 0.5 * PI * 0.63;
    let largest = largest_move(&frames);
    assert!(largest <= speed / FPS, "{largest} m in one frame");
}

#[test]
fn walking_mannequin_is_closed_clean_grounded_and_turns_a_quarter_turn() {
    let (frames, tris) = frames_n("mannequin_walk", 41);
    assert!((4000..=6500).contains(&tris.len()), "{}", tris.len());
    assert_closed(&tris, frames[0].vertex_count());
    // the arms held out (A-pose): the hands (centre 0.585 m from the shoulder joint at
    // x = ±0.21 m, 13.3° + 30° from the vertical, radius 0.045 m) reach
    // |x| = 0.21 + 0.585 sin(43.3°) + 0.045 ≈ 0.66 m; between the knees and the top of the
    // hips (y 0.45–1.0 m) nothing is between 0.3 m and 0.48 m from the vertical axis, in any
    // frame: the arms leave room for a skirt around the hips and legs
    let reach = frames[0]
        .positions
        .iter()
        .fold(0.0f64, |r, p| r.max(p.x.abs()));
    assert!(reach > 0.62 && reach < 0.7, "{reach}");
    let ground = frames[0]
        .positions
        .iter()
        .map(|p| p.y)
        .fold(f64::INFINITY, f64::min);
    assert!(ground > 0.0 && ground < 0.02, "{ground}");
    let mut swing = 0.0f64;
    for (k, m) in frames.iter().enumerate() {
        let n = count_self_intersections(&m.positions, &tris);
        assert_eq!(n, 0, "frame {}: {n} intersecting triangle pairs", k + 1);
        assert!(volume(&m.positions, &tris) > 0.0, "frame {}", k + 1);
        // the lower foot stays on the ground (6 printed decimals)
        let low = m
            .positions
            .iter()
            .map(|p| p.y)
            .fold(f64::INFINITY, f64::min);
        assert!(
            (low - ground).abs() < 2e-6,
            "frame {}: lowest point {low}",
            k + 1
        );
        for p in m.positions.iter().filter(|p| p.y > 0.45 && p.y < 1.0) {
            let r = p.x.hypot(p.z);
            assert!(!(0.3..0.48).contains(&r), "frame {}: {p}", k + 1);
        }
        // the legs swing: how far a foot gets from where it stands, seen from the body
        // (the body's rotation about y undone through the hand's angle)
        let (hand, hand0) = (
            m.positions[far(&frames[0])],
            frames[0].positions[far(&frames[0])],
        );
        let yaw = (-hand.z).atan2(hand.x) - (-hand0.z).atan2(hand0.x);
        let (c, s) = (yaw.cos(), yaw.sin());
        for (p, p0) in m.positions.iter().zip(&frames[0].positions) {
            if p0.y < 0.15 {
                let back = Vec3::new(c * p.x - s * p.z, p.y, s * p.x + c * p.z);
                swing = swing.max((back - *p0).length());
            }
        }
    }
    // thighs 0.87 m from hip to sole swinging by 20°: a foot moves 2 × 0.87 sin(10°) ≈ 0.3 m
    // at least; more with the knee bent
    assert!(swing > 0.25, "{swing}");
    // the whole body (the hands are not skinned to the legs) turns by exactly 90°
    let i = far(&frames[0]);
    let (p0, p1) = (frames[0].positions[i], frames[40].positions[i]);
    let yaw = (-p1.z).atan2(p1.x) - (-p0.z).atan2(p0.x);
    assert!((yaw - PI / 2.0).abs() < 1e-4, "{}", yaw.to_degrees());
}

/// The vertex farthest along +x (a fingertip of the right hand).
fn far(m: &Mesh) -> usize {
    (0..m.positions.len())
        .max_by(|&a, &b| m.positions[a].x.total_cmp(&m.positions[b].x))
        .unwrap()
}
