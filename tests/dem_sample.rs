//! Preparing DEM samples: random sequential addition, settling, CSV loading.
use grainflow::dem::{
    closed_box, load_csv, random_sequential_addition, settle, stable_time_step, ContactModel,
    DemError, DemSystem, SizeDistribution,
};

const SIZES: SizeDistribution = SizeDistribution::Uniform {
    min: 0.46e-3,
    max: 0.69e-3,
};

/// Grains lie inside the rectangle, never overlap, reach the requested solid fraction, and
/// the same seed gives the same sample (another seed another one).
#[test]
fn random_sequential_addition_packs_without_overlap() {
    let (lo, hi) = ([0.0, 0.0], [0.04, 0.02]);
    let g = random_sequential_addition(lo, hi, SIZES, 2500.0, 0.45, 1, 5000);
    let area: f64 = g.r.iter().map(|r| std::f64::consts::PI * r * r).sum();
    let fraction = area / (0.04 * 0.02);
    eprintln!("{} grains, solid fraction {fraction:.3}", g.len());
    assert!(fraction >= 0.45, "{fraction}");
    for i in 0..g.len() {
        assert!(g.x[i] - g.r[i] >= lo[0] && g.x[i] + g.r[i] <= hi[0]);
        assert!(g.y[i] - g.r[i] >= lo[1] && g.y[i] + g.r[i] <= hi[1]);
        assert!((0.46e-3..=0.69e-3).contains(&g.r[i]));
        for j in i + 1..g.len() {
            let d = (g.x[j] - g.x[i]).hypot(g.y[j] - g.y[i]);
            assert!(d >= g.r[i] + g.r[j], "grains {i} and {j} overlap");
        }
    }
    let again = random_sequential_addition(lo, hi, SIZES, 2500.0, 0.45, 1, 5000);
    assert_eq!(g.x, again.x);
    let other = random_sequential_addition(lo, hi, SIZES, 2500.0, 0.45, 2, 5000);
    assert_ne!(g.x, other.x);
}

/// Normal and bidisperse distributions stay within their bounds and proportions.
#[test]
fn size_distributions_respect_their_bounds() {
    let normal = SizeDistribution::Normal {
        mean: 0.5e-3,
        std: 0.1e-3,
        min: 0.4e-3,
        max: 0.6e-3,
    };
    let g = random_sequential_addition([0.0; 2], [0.05, 0.05], normal, 2500.0, 0.4, 3, 5000);
    assert!(g.r.iter().all(|r| (0.4e-3..=0.6e-3).contains(r)));
    let mean = g.r.iter().sum::<f64>() / g.len() as f64;
    assert!((mean / 0.5e-3 - 1.0).abs() < 0.03, "mean {mean}");
    let bi = SizeDistribution::Bidisperse {
        small: 0.4e-3,
        large: 0.8e-3,
        fraction_small: 0.7,
    };
    let g = random_sequential_addition([0.0; 2], [0.1, 0.1], bi, 2500.0, 0.3, 4, 5000);
    let small = g.r.iter().filter(|&&r| r == 0.4e-3).count() as f64 / g.len() as f64;
    assert!(g.r.iter().all(|&r| r == 0.4e-3 || r == 0.8e-3));
    assert!((small - 0.7).abs() < 0.05, "small fraction {small}");
}

/// A loose sample in a box settles under gravity: kinetic energy drops below the threshold
/// and the grains end up resting on each other.
#[test]
fn settling_under_gravity_comes_to_rest() {
    let l = 0.02;
    let g = random_sequential_addition([0.0; 2], [l, l], SIZES, 2500.0, 0.35, 5, 2000);
    let walls = closed_box([0.0, 0.0], [l, 2.0 * l], 0.5);
    let model = ContactModel {
        kn: 1e5,
        kt: 0.5e5,
        restitution: 0.5,
        friction: 0.5,
        rolling_friction: 0.0,
        tangential_damping: 0.0,
    };
    let dt = stable_time_step(&g, &model, 0.1);
    let mut s = DemSystem::new(g, walls, model, [0.0, -9.81], dt, 0.1, false).unwrap();
    let threshold = 1e-12;
    let steps = settle(&mut s, 50.0, threshold, 200_000);
    let n = s.grains.len();
    let ke = s.grains.kinetic_energy() / n as f64;
    eprintln!(
        "{n} grains settled in {steps} steps: KE per grain {ke:.2e} J/m, {:.2} contacts per grain",
        2.0 * s.contacts() as f64 / n as f64
    );
    assert!(steps < 200_000 && ke < threshold);
    assert!(
        s.contacts() as f64 >= n as f64,
        "a resting packing has contacts"
    );
    assert_eq!(s.global_damping, 0.0, "damping is off again after settling");
}

/// CSV of x, y, r with a header and comments loads; a bad row names its line.
#[test]
fn csv_loader_reads_rows_and_names_bad_lines() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("grains.csv");
    std::fs::write(&p, "x,y,r\n0.0, 0.0, 0.001 # first\n0.003,0.0,0.001\n\n").unwrap();
    let g = load_csv(&p, 2500.0).unwrap();
    assert_eq!(g.len(), 2);
    assert_eq!(g.x[1], 0.003);
    std::fs::write(&p, "0,0,0.001\n0.003,0,-1\n").unwrap();
    let e = load_csv(&p, 2500.0).unwrap_err();
    assert!(matches!(e, DemError::Input { line: 2, .. }), "{e}");
    assert!(e.to_string().contains("r > 0"), "{e}");
}
