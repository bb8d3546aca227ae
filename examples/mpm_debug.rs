use decomposition::SingleProcess;
use grainflow::mpm::MpmSystem;
use grainflow::scene::{load_any, AnyScene};
fn main() {
    let path = std::env::args().nth(1).unwrap();
    let AnyScene::Mpm(m) = load_any(std::path::Path::new(&path)).unwrap() else { panic!() };
    let mut sys = MpmSystem::new(m.setup.clone(), m.points().unwrap(), &SingleProcess).unwrap();
    let mut prev: Option<grainflow::mpm::Points> = None;
    loop {
        let snapshot = sys.points.clone();
        if let Err(e) = sys.step(&SingleProcess) { println!("{e}"); break; }
        let p = &sys.points;
        let (mut vmax, mut imax) = (0.0f64, 0);
        for i in 0..p.len() { let v = p.vel[i][0].hypot(p.vel[i][1]); if v > vmax { vmax = v; imax = i; } }
        if sys.steps % 250 == 0 {
            let k = p.id.iter().position(|&x| x == 4951).unwrap();
            println!("step {} t {:.4} vmax {vmax:.3} id {} | 4951 pos {:.4?} vel {:.3?} F {:.3?} s {:.0?} ep {:.2}", sys.steps, sys.time, p.id[imax], p.pos[k], p.vel[k], p.defgrad[k], p.stress[k], p.eps_p[k]);
        }
        if vmax > 3.0 {
            println!("step {} vmax {vmax} at id {} pos {:?} vel {:?} stress {:?} eps_p {} F {:?}", sys.steps, p.id[imax], p.pos[imax], p.vel[imax], p.stress[imax], p.eps_p[imax], p.defgrad[imax]);
            let id = p.id[imax];
            for q in [&snapshot].into_iter().chain(prev.iter()) {
                let k = q.id.iter().position(|&x| x == id).unwrap();
                println!("  before: pos {:?} vel {:?} stress {:?} F {:?}", q.pos[k], q.vel[k], q.stress[k], q.defgrad[k]);
            }
            // neighbours
            let c = p.pos[imax];
            for i in 0..p.len() { let d = (p.pos[i][0]-c[0]).hypot(p.pos[i][1]-c[1]); if d < 0.006 { println!("   nb id {} pos {:?} vel {:?} s {:?}", p.id[i], p.pos[i], p.vel[i], p.stress[i]); } }
            break;
        }
        prev = Some(snapshot);
    }
}
