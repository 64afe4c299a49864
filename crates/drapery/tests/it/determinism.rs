//! Same scene, same bits, whatever the thread count.

use crate::common::*;
use drapery::SolverSettings;
use drapery::model::MassSpec;

#[test]
fn a_hanging_cloth_gives_identical_bits_on_one_and_two_threads() {
    let run = |threads: usize| {
        on_threads(threads, || {
            let mut sim = hanging_cloth(
                48,
                SolverSettings::default(),
                material(MassSpec::Density(0.1)),
            );
            for _ in 0..10 {
                sim.step(1.0 / 60.0).unwrap();
            }
            bits(sim.model().positions())
        })
    };
    assert_eq!(run(1), run(2));
}
