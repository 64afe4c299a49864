//! Stitches: a sleeve sewn shut around an arm (`examples/stitched_tube.toml`) closes its seam
//! and nothing crosses.

mod common;
use common::run_and_check;
use drapery::Vec3;

/// The widest gap between the two vertices of a stitched pair.
fn widest(x: &[Vec3], pairs: &[(usize, usize)]) -> f64 {
    pairs
        .iter()
        .map(|&(a, b)| (x[a] - x[b]).length())
        .fold(0.0, f64::max)
}

#[test]
fn stitched_tube_closes_its_seam_and_nothing_crosses() {
    let (_t, scene, frames) = run_and_check("stitched_tube");
    let model = scene.model().expect("model");
    let pairs: Vec<(usize, usize)> = model
        .stitches()
        .iter()
        .map(|p| (p.a as usize, p.b as usize))
        .collect();
    assert_eq!(pairs.len(), 21, "one pair per row of the sleeve");
    let thickness = scene.collision.expect("collisions on").thickness;
    // open at the start: one chord (26 mm) apart
    assert!(widest(&frames[0], &pairs) > 0.025);
    // closed after 0.5 s, and for the rest of the run
    let closed = (scene.frame_rate * 0.5) as usize;
    for (k, x) in frames.iter().enumerate().skip(closed) {
        let w = widest(x, &pairs);
        assert!(w < thickness, "frame {k}: a stitched pair is {w} m apart");
    }
    // the sleeve fell onto the arm and hangs from it: it moved down, and its lowest point is
    // below the capsule's axis (y = 1 m) while its highest rests above the capsule's top
    let last = frames.last().unwrap();
    let (lo, hi) = last
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
            (l.min(p.y), h.max(p.y))
        });
    let hi0 = frames[0].iter().fold(f64::NEG_INFINITY, |h, p| h.max(p.y));
    assert!(
        hi < hi0 - 0.01 && hi > 1.05 && lo < 1.0,
        "top {hi} (from {hi0}), bottom {lo}"
    );
}
