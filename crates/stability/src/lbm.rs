//! The fluid's stability map, measured: two test flows (a periodic double shear layer and a
//! lid-driven cavity) on a small lattice, run for a fixed number of steps at each relaxation
//! time τ, lattice Mach number and collision operator, each classified stable or blown up.

use lbm::collision::Collision;
use lbm::lattice::{FaceCondition, LatticeSetup, SolidInfo};
use lbm::Lattice;

/// Lattice speed of sound 1/√3.
pub const CS: f64 = 0.577_350_269_189_625_8;
/// Smagorinsky constant of the operators "with Smagorinsky".
pub const SMAGORINSKY: f64 = 0.1;

/// A collision operator of the map: family and whether the Smagorinsky closure is on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Operator {
    /// "bgk", "trt" or "mrt".
    pub family: &'static str,
    /// Smagorinsky closure on.
    pub smagorinsky: bool,
}

impl Operator {
    /// The six operators of the map.
    pub const ALL: [Operator; 6] = [
        Operator::new("bgk", false),
        Operator::new("bgk", true),
        Operator::new("trt", false),
        Operator::new("trt", true),
        Operator::new("mrt", false),
        Operator::new("mrt", true),
    ];

    const fn new(family: &'static str, smagorinsky: bool) -> Self {
        Self {
            family,
            smagorinsky,
        }
    }

    /// The map's operator of a lattice's collision model, with or without the closure (its
    /// rates may differ from the measured ones: [`Operator::measured`]).
    pub fn of(c: &Collision, smagorinsky: bool) -> Self {
        let family = match c {
            Collision::Bgk => "bgk",
            Collision::Trt { .. } => "trt",
            Collision::Mrt { .. } => "mrt",
        };
        Self::new(family, smagorinsky)
    }

    /// The collision model measured for this operator.
    pub fn collision(&self) -> Collision {
        match self.family {
            "trt" => Collision::Trt { magic: 3.0 / 16.0 },
            "mrt" => Collision::Mrt {
                s_e: 1.4,
                s_eps: 1.4,
                s_q: None,
            },
            _ => Collision::Bgk,
        }
    }

    /// Whether `collision` with Smagorinsky constant `smagorinsky` is this operator with the
    /// rates the map measured (so the map judges it; otherwise it is measured on the spot).
    pub fn measured(&self, collision: &Collision, smagorinsky: Option<f64>) -> bool {
        *collision == self.collision() && smagorinsky == self.smagorinsky.then_some(SMAGORINSKY)
    }

    /// Name in the map's CSV ("bgk", "bgk+smag", …).
    pub fn name(&self) -> String {
        if self.smagorinsky {
            format!("{}+smag", self.family)
        } else {
            self.family.to_string()
        }
    }
}

/// One of the two test flows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flow {
    /// Doubly periodic double shear layer (Minion & Brown 1997): thin layers that roll up.
    ShearLayer,
    /// Lid-driven square cavity.
    Cavity,
}

impl Flow {
    /// Both flows.
    pub const ALL: [Flow; 2] = [Flow::ShearLayer, Flow::Cavity];

    /// Name in the map's CSV.
    pub fn name(&self) -> &'static str {
        match self {
            Flow::ShearLayer => "shear-layer",
            Flow::Cavity => "cavity",
        }
    }
}

/// One measured point of the map.
#[derive(Debug, Clone, PartialEq)]
pub struct Sample {
    /// Test flow.
    pub flow: Flow,
    /// Operator.
    pub operator: Operator,
    /// Relaxation time τ.
    pub tau: f64,
    /// Lattice Mach number U / c_s of the driving velocity.
    pub mach: f64,
    /// Whether it ran `steps` steps with densities positive and speeds below c_s·√3 (= 1).
    pub stable: bool,
}

impl Sample {
    /// Reynolds number per cell U Δx / ν of this point.
    pub fn re_cell(&self) -> f64 {
        self.mach * CS / ((self.tau - 0.5) / 3.0)
    }
}

/// A collision operator with all its rates: the map's [`Operator`]s, or a scene's own.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rates {
    /// The collision model and its rates.
    pub collision: Collision,
    /// The Smagorinsky constant C_s, if the closure is on.
    pub smagorinsky: Option<f64>,
}

impl From<Operator> for Rates {
    fn from(op: Operator) -> Self {
        Self {
            collision: op.collision(),
            smagorinsky: op.smagorinsky.then_some(SMAGORINSKY),
        }
    }
}

/// The lattice of `flow` on an `n × n` grid at relaxation time `tau`, driving velocity
/// `mach` c_s, with `op`; and the initial velocity of each cell.
fn setup(flow: Flow, n: usize, tau: f64, mach: f64, op: Rates) -> (LatticeSetup, Vec<[f64; 2]>) {
    let u = mach * CS;
    let base = LatticeSetup {
        nx: n,
        ny: n,
        cells: vec![0; n * n],
        faces: std::array::from_fn(|_| FaceCondition::Periodic),
        solids: Vec::new(),
        collision: op.collision,
        tau0: tau,
        smagorinsky: op.smagorinsky,
        force: [0.0; 2],
    };
    match flow {
        Flow::ShearLayer => {
            // Minion & Brown 1997: u_x = U tanh(κ(y − ¼)) below ½, U tanh(κ(¾ − y)) above,
            // u_y = δ U sin(2π(x + ¼)), κ = 80, δ = 0.05 (lengths in units of the box).
            let (kappa, delta) = (80.0, 0.05);
            let init = (0..n * n)
                .map(|k| {
                    let (x, y) = ((k % n) as f64 + 0.5, (k / n) as f64 + 0.5);
                    let (xs, ys) = (x / n as f64, y / n as f64);
                    let ux = if ys <= 0.5 {
                        u * (kappa * (ys - 0.25)).tanh()
                    } else {
                        u * (kappa * (0.75 - ys)).tanh()
                    };
                    let uy = delta * u * (2.0 * std::f64::consts::PI * (xs + 0.25)).sin();
                    [ux, uy]
                })
                .collect();
            (base, init)
        }
        Flow::Cavity => {
            let wall = |name: &str, v: [f64; 2]| SolidInfo {
                name: name.into(),
                velocity: v,
            };
            let setup = LatticeSetup {
                faces: [
                    FaceCondition::Wall { solid: 1 },
                    FaceCondition::Wall { solid: 1 },
                    FaceCondition::Wall { solid: 1 },
                    FaceCondition::Wall { solid: 2 },
                ],
                solids: vec![wall("walls", [0.0; 2]), wall("lid", [u, 0.0])],
                ..base
            };
            (setup, vec![[0.0; 2]; n * n])
        }
    }
}

/// The largest speed a stable run may reach, as a multiple of its driving speed: both test
/// flows stay below their driving speed when resolved, and a run that overshoots it by half
/// is finite but not physical (an under-resolved BGK cavity at τ → ½ reaches 2–3 times the
/// lid speed next to the lid).
pub const OVERSPEED: f64 = 1.5;

/// Run one point: `steps` steps of `flow` on an `n × n` lattice (f64, one thread: points run
/// in parallel). Stable when no density went NaN or non-positive and the speed stayed below
/// [`OVERSPEED`] times the driving speed and below 1 (√3 c_s) everywhere, checked every 100
/// steps and at the end.
pub fn run_point(flow: Flow, op: Operator, tau: f64, mach: f64, n: usize, steps: usize) -> bool {
    run_rates(flow, op.into(), tau, mach, n, steps)
}

/// [`run_point`] with any operator's rates.
pub fn run_rates(flow: Flow, op: Rates, tau: f64, mach: f64, n: usize, steps: usize) -> bool {
    let (s, init) = setup(flow, n, tau, mach, op);
    let limit = (OVERSPEED * mach * CS).min(1.0);
    let mut lat = Lattice::<f64>::new(s);
    for (k, u) in init.iter().enumerate() {
        lat.set_equilibrium(k % n, k / n, 1.0, *u);
    }
    lat.update_boundaries();
    for step in 1..=steps {
        if lat.step().is_err() {
            return false;
        }
        if step % 100 == 0 || step == steps {
            let f = lat.fields();
            let fast = f.ux.iter().zip(&f.uy).any(|(a, b)| !(a.hypot(*b) < limit));
            if fast {
                return false;
            }
        }
    }
    true
}

/// Measure every (flow, operator, τ, Mach) of the grid on an `n × n` lattice for `steps`
/// steps, one point per worker at a time. Each worker is an OS thread with its own one-thread
/// pool, built once: installing a fresh pool from inside a pool's worker would let the
/// waiting worker start another point on its own stack, nesting without bound.
pub fn sweep(taus: &[f64], machs: &[f64], n: usize, steps: usize) -> Vec<Sample> {
    use std::sync::atomic::{AtomicUsize, Ordering};
    let mut points = Vec::new();
    for flow in Flow::ALL {
        for op in Operator::ALL {
            for &tau in taus {
                for &mach in machs {
                    points.push((flow, op, tau, mach));
                }
            }
        }
    }
    let next = AtomicUsize::new(0);
    let workers = rayon::current_num_threads().max(1);
    let mut stable = vec![false; points.len()];
    std::thread::scope(|scope| {
        let handles: Vec<_> = (0..workers)
            .map(|_| {
                scope.spawn(|| {
                    let mut done = Vec::new();
                    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build();
                    loop {
                        let k = next.fetch_add(1, Ordering::Relaxed);
                        let Some(&(flow, op, tau, mach)) = points.get(k) else {
                            break;
                        };
                        let run = || run_point(flow, op, tau, mach, n, steps);
                        let ok = match &pool {
                            Ok(p) => p.install(run),
                            Err(_) => run(),
                        };
                        done.push((k, ok));
                    }
                    done
                })
            })
            .collect();
        for h in handles {
            for (k, ok) in h.join().expect("a map worker panicked") {
                stable[k] = ok;
            }
        }
    });
    points
        .into_iter()
        .zip(stable)
        .map(|((flow, operator, tau, mach), stable)| Sample {
            flow,
            operator,
            tau,
            mach,
            stable,
        })
        .collect()
}
