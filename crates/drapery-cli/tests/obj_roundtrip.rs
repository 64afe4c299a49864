//! Output OBJ files read back to the very same f64 values, topology and order.

use drapery::io::obj::{read_obj, write_obj};
use drapery::model::ClothInfo;
use drapery::{Face, Mesh, Vec3};

#[test]
fn written_frames_read_back_to_identical_f64_bits_across_several_cloths() {
    let awkward = [
        0.1 + 0.2,
        1e-300,
        -0.0,
        5e-324,
        f64::MIN_POSITIVE,
        1.0 / 3.0,
        -2.0 / 3.0,
        123_456_789.123_456_79,
        9007199254740993.0,
        -1.7976931348623157e308,
        2.5e-8,
        1e21,
    ];
    let sheet = Mesh {
        positions: vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.5, 2.0, 0.0),
        ],
        faces: vec![Face::Quad([0, 1, 2, 3]), Face::Tri([3, 2, 4])],
        lines: vec![[4, 0]],
        face_uv: Vec::new(),
    };
    let rope = Mesh {
        positions: vec![
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(0.0, 0.0, 2.0),
            Vec3::new(0.0, 0.0, 3.0),
        ],
        faces: vec![],
        lines: vec![[0, 1], [1, 2]],
        face_uv: Vec::new(),
    };
    let cloths = vec![
        ClothInfo {
            material: Default::default(),
            name: "sheet".into(),
            offset: 0,
            mesh: sheet.clone(),
        },
        ClothInfo {
            material: Default::default(),
            name: "rope".into(),
            offset: 5,
            mesh: rope.clone(),
        },
    ];
    // A "simulated" state full of awkward values.
    let x: Vec<Vec3> = (0..8)
        .map(|i| {
            Vec3::new(
                awkward[i % awkward.len()],
                awkward[(i + 4) % awkward.len()],
                awkward[(i + 8) % awkward.len()],
            )
        })
        .collect();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("frame_00000.obj");
    // The read-back mesh is validated, so write a valid state (the input) first, then check the
    // awkward values through the text path directly.
    let rest: Vec<Vec3> = sheet
        .positions
        .iter()
        .chain(&rope.positions)
        .copied()
        .collect();
    write_obj(&path, &cloths, &rest).unwrap();
    let back = read_obj(&path).unwrap();
    assert_eq!(back.positions, rest);
    assert_eq!(
        back.faces,
        vec![Face::Quad([0, 1, 2, 3]), Face::Tri([3, 2, 4])]
    );
    assert_eq!(back.lines, vec![[4, 0], [5, 6], [6, 7]]);
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains("\no sheet\n") && text.contains("\no rope\n"));
    assert!(text.find("o sheet").unwrap() < text.find("o rope").unwrap());
    // no temporary files left behind
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);

    // Awkward values: only lines, so no face can be "degenerate".
    let points = ClothInfo {
        material: Default::default(),
        name: "points".into(),
        offset: 0,
        mesh: Mesh {
            positions: x.clone(),
            faces: vec![],
            lines: (0..7).map(|i| [i, i + 1]).collect(),
            face_uv: Vec::new(),
        },
    };
    let path2 = dir.path().join("awkward.obj");
    write_obj(&path2, std::slice::from_ref(&points), &x).unwrap();
    let back = read_obj(&path2).unwrap();
    assert_eq!(back.positions.len(), x.len());
    for (a, b) in x.iter().zip(&back.positions) {
        for k in 0..3 {
            assert_eq!(
                a[k].to_bits(),
                b[k].to_bits(),
                "{} came back as {}",
                a[k],
                b[k]
            );
        }
    }
}
