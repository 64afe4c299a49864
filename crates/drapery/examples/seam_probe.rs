use drapery::scene::Scene;
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a: Vec<String> = std::env::args().collect();
    let scene = Scene::load(std::path::Path::new(&a[1]))?;
    let steps: usize = a[2].parse()?;
    let mut sim = scene.build()?;
    let h = scene.step_size();
    let pre = scene.preroll_steps();
    let steps = if steps == 0 {
        pre + scene.step_count()
    } else {
        steps
    };
    let tris = sim.model().triangles();
    let sewn: Vec<[u32; 2]> = sim.model().stitches().iter().map(|s| [s.a, s.b]).collect();
    let mut last = 0;
    let seams = drapery::collision::seams::Seams::new(sim.positions().len(), &tris, &sewn);
    for s in 0..steps {
        let r = if s < pre {
            sim.preroll(1, h)?;
            None
        } else {
            Some(sim.step(h)?)
        };
        let x = sim.positions();
        if s + 1 == pre || s + 1 == steps {
            let gaps: Vec<f64> = sim
                .model()
                .stitches()
                .iter()
                .map(|t| (x[t.a as usize] - x[t.b as usize]).length())
                .collect();
            let mut g = gaps.clone();
            g.sort_by(f64::total_cmp);
            for (k, t) in sim.model().stitches().iter().enumerate() {
                if gaps[k] > 0.01 {
                    println!(
                        "  stitch {} {} gap {:.3} at {:?} {:?}",
                        t.a, t.b, gaps[k], x[t.a as usize], x[t.b as usize]
                    );
                }
            }
            println!(
                "step {s}: stitch gaps median {:.2e} p99 {:.2e} max {:.2e} (of {})",
                g[g.len() / 2],
                g[g.len() * 99 / 100],
                g[g.len() - 1],
                g.len()
            );
        }
        let pairs = drapery::collision::check::sewn_intersecting_pairs(x, &tris, &sewn);
        if pairs.len() != last
            || r.as_ref()
                .map_or(false, |r| r.ccd_hits > 0 && std::env::var("ALL").is_ok())
        {
            println!(
                "step {s} (pre {}) pairs {} {:?} ccd {:?}",
                s < pre,
                pairs.len(),
                &pairs[..pairs.len().min(6)]
                    .iter()
                    .map(|&[p, q]| (tris[p as usize], tris[q as usize]))
                    .collect::<Vec<_>>(),
                r.map(|r| r.ccd_hits)
            );
            last = pairs.len();
            for &[p, q] in &pairs {
                let (a, b) = (tris[p as usize], tris[q as usize]);
                let mut ex = Vec::new();
                for v in a {
                    ex.push(seams.exempt(&[v, b[0], b[1], b[2]]));
                }
                for v in b {
                    ex.push(seams.exempt(&[v, a[0], a[1], a[2]]));
                }
                for i in 0..3 {
                    for j in 0..3 {
                        ex.push(seams.exempt(&[a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3]]));
                    }
                }
                println!(
                    "   exempt {:?}",
                    ex.iter().map(|&e| e as u8).collect::<Vec<_>>()
                );
            }
        }
    }
    Ok(())
}
