//! The sleeveless top (`examples/top.toml`): four GarmentCode panels sewn around the
//! mannequin's torso in the pre-roll, then carried through its turn and arm raise; every frame
//! free of intersections (`drapery check --scene`).

mod common;
use common::{Out, examples, run_and_check, stitch_gaps};
use drapery::Vec3;
use drapery::io::obj::read_obj;
use std::path::{Path, PathBuf};

/// The angle (rad) that turns the points `a` onto the points `b` about the vertical axis through
/// the origin, in the least-squares sense (the 2-D Kabsch angle in the x–z plane).
fn turn(a: &[Vec3], b: &[Vec3]) -> f64 {
    let (mut s, mut c) = (0.0, 0.0);
    for (p, q) in a.iter().zip(b) {
        s += p.z * q.x - p.x * q.z;
        c += p.x * q.x + p.z * q.z;
    }
    s.atan2(c)
}

/// The widest angular gap (rad) around the vertical axis between the points at height
/// `lo < y < hi`.
fn widest_gap(x: &[Vec3], lo: f64, hi: f64) -> f64 {
    let mut a: Vec<f64> = (x.iter())
        .filter(|p| p.y > lo && p.y < hi)
        .map(|p| p.x.atan2(p.z))
        .collect();
    assert!(a.len() > 10, "{} points in the band", a.len());
    a.sort_by(f64::total_cmp);
    let wrap = a[0] + std::f64::consts::TAU - a[a.len() - 1];
    a.windows(2).map(|w| w[1] - w[0]).fold(wrap, f64::max)
}

#[test]
fn top_is_sewn_around_the_torso_and_turns_with_the_body() {
    let (_t, scene, frames) = run_and_check("top");
    let names: Vec<&str> = scene.cloths.iter().map(|c| c.name.as_str()).collect();
    assert!(names.len() >= 4, "{names:?}");
    assert!(names.iter().all(|n| n.starts_with("top.")), "{names:?}");
    let model = scene.model().unwrap();
    let stitches = model.stitches();
    assert!(stitches.len() >= 40, "{}", stitches.len());
    let th = scene.collision.unwrap().thickness;
    let edge_length = 0.03; // examples/top.toml
    // the front and back panels start 0.34 m apart; after the pre-roll (frame 0) and at the
    // end every stitched pair is closer than half an edge (the seam closed to within the mesh's
    // spacing) and nine in ten are closer than the collision thickness
    let gaps = |x: &[Vec3]| stitch_gaps(stitches, x);
    let initial = model.positions();
    let widest = gaps(initial).into_iter().fold(0.0, f64::max);
    assert!(widest > 0.3, "{widest}");
    for k in [0, frames.len() - 1] {
        let g = gaps(&frames[k]);
        let widest = g.iter().copied().fold(0.0, f64::max);
        assert!(widest < 0.5 * edge_length, "frame {k}: {widest}");
        let open = g.iter().filter(|&&d| d >= th).count();
        assert!(
            10 * open <= g.len(),
            "frame {k}: {open} of {} pairs open",
            g.len()
        );
    }
    // flat, the panels leave the sides of the chest open; sewn, they close round it: at chest
    // height (y 1.1–1.2 m) no gap around the body's axis is wider than 0.5 rad in any frame
    assert!(widest_gap(initial, 1.1, 1.2) > 1.0);
    // the mannequin (scripts/make_mannequin.py): shoulders' top at 1.37 + 0.075 m, hips from
    // 0.84 m, chest of radius 0.14 m about the vertical axis (hips and arms reach 0.19 m)
    let shoulders = 1.445;
    let start_top = initial
        .iter()
        .map(|p| p.y)
        .fold(f64::NEG_INFINITY, f64::max);
    for (k, x) in frames.iter().enumerate() {
        let gap = widest_gap(x, 1.1, 1.2);
        assert!(gap < 0.5, "frame {k}: a gap of {gap} rad round the chest");
        // it hangs from the shoulders: the straps, sewn over them, rest there (neither slid
        // off nor riding up above where they started flat), nothing slides to the hips
        let (lo, hi) = x
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p.y), hi.max(p.y))
            });
        assert!(
            hi > shoulders - 0.03 && hi < start_top,
            "frame {k}: top at y = {hi}"
        );
        assert!(lo > 0.9, "frame {k}: hem at y = {lo}");
        // and stays close round the body
        let r = x.iter().map(|p| p.x.hypot(p.z)).fold(0.0, f64::max);
        assert!(r < 0.26, "frame {k}: a vertex {r} m from the body's axis");
    }
    // the body turns about the vertical axis (measured on its legs, which only turn); the top
    // turns with it
    let body = |k: usize| {
        read_obj(&examples().join(format!("mannequin/mannequin_{:04}.obj", k + 1)))
            .unwrap()
            .positions
    };
    let rest = body(0);
    let legs: Vec<usize> = (0..rest.len()).filter(|&i| rest[i].y < 0.6).collect();
    let pick = |x: &[Vec3]| legs.iter().map(|&i| x[i]).collect::<Vec<_>>();
    let legs0 = pick(&rest);
    let mut largest = 0.0f64;
    for (k, x) in frames.iter().enumerate() {
        let body_turn = turn(&legs0, &pick(&body(k)));
        let top_turn = turn(&frames[0], x);
        largest = largest.max(body_turn.abs());
        assert!(
            (top_turn - body_turn).abs() < 0.1,
            "frame {k}: the body turned {body_turn} rad, the top {top_turn} rad"
        );
    }
    assert!(largest > 0.45, "the body turns at most {largest} rad");
}

/// `examples/top.toml` with `edge_length` and `duration` changed, written beside its run
/// folder: the folder, the scene and the run's output.
fn top_at(edge_length: &str, duration: &str) -> (tempfile::TempDir, PathBuf, PathBuf, Out) {
    let dir = examples();
    let mut scene = std::fs::read_to_string(dir.join("top.toml")).unwrap();
    for (from, to) in [
        (
            "edge_length = 0.03 ",
            format!("edge_length = {edge_length} "),
        ),
        ("duration = 2.0", format!("duration = {duration}")),
        ("\"garments/", format!("\"{}/garments/", dir.display())),
        ("\"mannequin/", format!("\"{}/mannequin/", dir.display())),
    ] {
        assert_eq!(scene.matches(from).count(), 1, "{from}");
        scene = scene.replace(from, &to);
    }
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("top_variant.toml");
    std::fs::write(&path, scene).unwrap();
    let out = tmp.path().join("out");
    let r = common::drapery(&common::run_args(&path, &out, &[]));
    (tmp, path, out, r)
}

/// `drapery check --scene`'s output for a run of `top_at`.
fn check(out: &Path, scene: &Path) -> Out {
    common::drapery(&[
        "check".as_ref(),
        out.as_os_str(),
        "--scene".as_ref(),
        scene.as_os_str(),
    ])
}

/// The top at 1.5 cm edges: in its 14th step after the pre-roll a vertex carried by the
/// turning mannequin (pressed between arm and torso) runs into the cloth beside it, whose
/// vertices are back at their start; the run stopped there ("collisions could not be resolved
/// … keep colliding with their vertices back at the start of the step") until that cloth went
/// along with the carried vertex (`collision::failsafe`'s groups). It now runs on, with no
/// intersection.
#[test]
fn the_top_at_finer_edges_runs_past_a_vertex_carried_into_its_cloth() {
    let (_tmp, path, out, r) = top_at("0.015", "0.1");
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    // (and, since seam crossings are pulled back too, nothing crosses)
    let c = check(&out, &path);
    assert_eq!(c.code, Some(0), "{}", c.stdout);
    assert!(c.stdout.contains("4 frames"), "{}", c.stdout);
}

/// The top at 2.5 cm edges: in the pre-roll the back panel's edge by the left armpit, pulled
/// to its partner, cut through the front panel's triangles beside the seam (which are let
/// through it so that the seam can close) and stayed crossed, five triangle pairs at frame 0
/// and in every frame after. The fail-safe now pulls back what crosses by a seam
/// (`collision::seam_crossings`): every frame is free of intersections, and the run says
/// nothing of its start.
#[test]
fn the_top_at_other_edges_closes_its_seams_without_crossing() {
    let (_tmp, path, out, r) = top_at("0.025", "0.1");
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert_eq!(r.stderr, "", "no warning");
    let c = check(&out, &path);
    assert_eq!(c.code, Some(0), "{}", c.stdout);
    assert!(c.stdout.contains("4 frames"), "{}", c.stdout);
}
