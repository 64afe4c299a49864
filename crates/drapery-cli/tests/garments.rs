//! Garments end to end: a GarmentCode pattern loaded by `[[garment]]`, its panels sewn during
//! the pre-roll around an animated mannequin, every frame free of intersections
//! (`drapery check --scene`).

mod common;
use common::{assert_rejected, run_and_check, stitch_gaps, yaw};
use drapery::Vec3;

/// The skirt (examples/skirt.toml): two flat panels 0.34 m apart in front of and behind the
/// walking mannequin (examples/mannequin_walk/), sewn during the 1 s pre-roll, then carried
/// while the body walks in place and turns a quarter turn to its left.
#[test]
fn skirt_is_sewn_around_the_hips_and_rides_the_walking_turning_mannequin() {
    let (_t, scene, frames) = run_and_check("skirt");
    let names: Vec<&str> = scene.cloths.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["skirt.skirt_front", "skirt.skirt_back"]);
    let model = scene.model().unwrap();
    let stitches = model.stitches();
    assert!(stitches.len() >= 20, "{}", stitches.len());
    let th = scene.collision.unwrap().thickness;
    // after the pre-roll (frame 0) and at the end every stitched pair is closer than the
    // collision thickness
    let initial = model.positions();
    let widest = |x: &[Vec3]| stitch_gaps(stitches, x).into_iter().fold(0.0, f64::max);
    assert!(widest(initial) > 0.3, "{}", widest(initial));
    for k in [0, frames.len() - 1] {
        assert!(widest(&frames[k]) < th, "frame {k}: {}", widest(&frames[k]));
    }
    // The waistband: the vertices that start within 4 cm of the panels' top (1.10 m, Bézier
    // waists within 1.2 cm of it). The mannequin's hips are widest (a convex perimeter of
    // 1.02 m) at y = 0.95–0.97 m in its rest pose, wider than the waistband (2 × 47 cm and its
    // curves, about 0.95 m), and the walking body only ever drops (its lower foot kept on the
    // ground), by less than 6 cm: held up by the hips, the waistband stays above
    // 0.95 - 0.06 = 0.89 m in every frame. It rests on the body: at least half of it within
    // 1 cm of the surface (contact is at the 4 mm thickness), none of it farther than 5 cm
    // (where it spans, as a belt would, the hollows between the chest and the hips).
    let waist: Vec<usize> = (0..initial.len())
        .filter(|&i| initial[i].y > 1.06)
        .collect();
    assert!(waist.len() >= 20, "{}", waist.len());
    let body = &scene.obstacles[0].collider;
    assert!(body.shape.deforms());
    // the body's turn: a fingertip of its right hand (the arms turn with the body only)
    let (rest, _) = body.surface(0.0).unwrap();
    let tip = (0..rest.len())
        .max_by(|&a, &b| rest[a].x.total_cmp(&rest[b].x))
        .unwrap();
    for (k, x) in frames.iter().enumerate() {
        let t = k as f64 / scene.frame_rate;
        let mut near = 0;
        for &i in &waist {
            let d = body.closest(x[i], t).signed_distance;
            assert!(
                x[i].y > 0.89 && d < 0.05,
                "frame {k}: waist vertex {i} at {} ({d} m from the body)",
                x[i]
            );
            near += usize::from(d < 0.01);
        }
        assert!(
            2 * near >= waist.len(),
            "frame {k}: {near} of {} waist vertices within 1 cm",
            waist.len()
        );
        // nothing reaches the ground: the hem, 0.5–0.58 m below the waist, swings above it
        let low = x.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
        assert!(low > 0.25, "frame {k}: {low}");
        // the skirt turns with the body: its mean turn about the vertical axis since frame 0
        // (vertices over 5 cm from the axis) stays within 15° of the body's
        let (posed, _) = body.surface(t).unwrap();
        let turned = yaw(rest[tip], posed[tip]);
        let moved: Vec<f64> = (0..x.len())
            .filter(|&i| frames[0][i].x.hypot(frames[0][i].z) > 0.05)
            .map(|i| yaw(frames[0][i], x[i]))
            .collect();
        let mean = moved.iter().sum::<f64>() / moved.len() as f64;
        assert!(
            (mean - turned).abs() < 15f64.to_radians(),
            "frame {k}: skirt {mean}, body {turned} rad"
        );
        if k + 1 == frames.len() {
            // the body has turned a quarter turn (by 1.6 s) and the skirt with it
            assert!(
                (turned - std::f64::consts::FRAC_PI_2).abs() < 1e-3,
                "{turned}"
            );
        }
    }
}

#[test]
fn bad_garments_are_named() {
    let g = "[[garment]]\nname = \"g\"\nedge_length = 0.05\ndensity = 0.1\n";
    assert_rejected(
        &format!("{g}pattern = \"nope.json\"\n"),
        &[],
        &["nope.json"],
    );
    assert_rejected(
        &format!("{g}pattern = \"p.json\"\n"),
        &[("p.json", "{\"hello\": 1}")],
        &["p.json"],
    );
    assert_rejected(
        &format!("{g}pattern = \"p.json\"\nseams = 3\n"),
        &[],
        &["garment[0].seams: unknown key of [[garment]]"],
    );
}
