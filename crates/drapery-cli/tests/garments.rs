//! Garments end to end: a GarmentCode pattern loaded by `[[garment]]`, its panels sewn during
//! the pre-roll, every frame free of intersections (`drapery check --scene`).

mod common;
use common::{assert_rejected, run_and_check};

#[test]
fn skirt_panels_are_sewn_in_the_preroll_and_settle_on_the_hips() {
    let (_t, scene, frames) = run_and_check("skirt");
    let names: Vec<&str> = scene.cloths.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["skirt.skirt_front", "skirt.skirt_back"]);
    let model = scene.model().unwrap();
    let stitches = model.stitches();
    assert!(stitches.len() >= 20, "{}", stitches.len());
    let th = scene.collision.unwrap().thickness;
    // the panels start 0.3 m apart; after the pre-roll (frame 0) and at the end every stitched
    // pair is closer than the collision thickness
    let initial = model.positions();
    let widest = |x: &[drapery::Vec3]| {
        stitches
            .iter()
            .map(|s| (x[s.a as usize] - x[s.b as usize]).length())
            .fold(0.0, f64::max)
    };
    assert!(widest(initial) > 0.25, "{}", widest(initial));
    for k in [0, frames.len() - 1] {
        assert!(widest(&frames[k]) < th, "frame {k}: {}", widest(&frames[k]));
    }
    // it rests on the hips (a sphere of radius 0.14 at y = 0.85): nothing fell to the ground
    let last = frames.last().unwrap();
    let min_y = last.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
    assert!(min_y > 0.3, "{min_y}");
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
