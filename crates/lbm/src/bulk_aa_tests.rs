//! Tests of the in-place bulk kernels' partially saturated cells and wall runs against the
//! two-array kernel's, and of the loads they sum per body.

use super::super::collision::Collision;
use super::super::lattice::{FaceCondition, Lattice, LatticeSetup, SolidInfo, FLUID};
use super::super::moving::{
    cell_centre, BodyColumns, MovingCells, PsmPlan, RigidMotion, SolidShare, NO_SLOT,
};
use super::*;
use decomposition::SingleProcess;

/// Columns 30–33 of rows 3–6 are an obstacle: those rows have two bulk runs.
fn obstacle(x: usize, y: usize) -> bool {
    (30..34).contains(&x) && (3..7).contains(&y)
}

/// A walled box with an obstacle and a varied flow.
fn lattice<T: Real>(collision: Collision) -> Lattice<T> {
    lattice_with(collision, 2)
}

/// [`lattice`] built with `buffers` population buffers (1: built to go in place).
fn lattice_with<T: Real>(collision: Collision, buffers: usize) -> Lattice<T> {
    let (nx, ny) = (61, 9);
    let cells = (0..nx * ny)
        .map(|k| if obstacle(k % nx, k / nx) { 1 } else { FLUID })
        .collect();
    let setup = LatticeSetup {
        nx,
        ny,
        cells,
        faces: std::array::from_fn(|_| FaceCondition::Wall { solid: 1 }),
        solids: vec![SolidInfo {
            name: "walls".into(),
            velocity: [0.0; 2],
        }],
        collision,
        tau0: 0.63,
        smagorinsky: None,
        force: [1e-6, -2e-6],
    };
    let whole = decomposition::SlabPartition::uniform(nx, 1).unwrap();
    let mut lat = if buffers == 1 {
        Lattice::<T>::new_slab_one_buffer(&setup, &whole, 0)
    } else {
        Lattice::<T>::new_slab(&setup, &whole, 0)
    };
    for y in 0..ny {
        for x in (0..nx).filter(|&x| !obstacle(x, y)) {
            let a = (x * 7 + y * 3) as f64;
            let u = [0.04 * (0.3 * a).sin(), 0.03 * (0.7 * a).cos()];
            lat.set_equilibrium(x, y, 1.0 + 0.01 * (0.5 * a).sin(), u);
        }
    }
    lat.update_boundaries();
    lat
}

/// Partially saturated cells in all rows but one: next to the walls and the obstacle
/// (special cells), a long stretch whose alignment to the kernel's chunks changes from
/// row to row, lone cells with empty chunks between them, the first and last columns of
/// even rows; in every
/// third row, every fifth cell shared by two solids (blended in lanes by share layer); one
/// cell in twelve fully covered (B = 1), and every other shared cell.
fn plan<T: Real>(lat: &Lattice<T>) -> PsmPlan {
    let (nx, ny) = (lat.nx(), lat.ny());
    let mut plan = PsmPlan::default();
    plan.clear();
    for y in 0..ny {
        plan.rows.push(plan.cells.len() as u32);
        for x in 0..nx {
            // Odd rows leave the runs' first or last chunks plain.
            let even = y % 2 == 0;
            let take = (x < 3 && even)
                || (4 + y..=20 + y).contains(&x)
                || x == 27
                || (34..=36).contains(&x)
                || x == 47
                || (x + 2 >= nx && even);
            if !take || y == 7 || obstacle(x, y) {
                continue;
            }
            let n = plan.cells.len();
            plan.cells.push(((y + 1) * lat.stride + x + 1) as u32);
            let two = y % 3 == 0 && n % 5 == 0;
            // Weights 0.05–0.95, and 1 (a fully covered cell) where the pattern gives 11
            // and at every other shared cell.
            let b = match (x + 3 * y) % 12 {
                _ if two && n % 10 == 0 => 1.0,
                11 => 1.0,
                v => 0.05 + 0.9 * v as f64 / 10.0,
            };
            let parts: &[f64] = if two { &[0.6, 0.4] } else { &[1.0] };
            for (s, part) in parts.iter().enumerate() {
                // A body per share, spinning about a point off the cell.
                plan.shares.push(SolidShare {
                    b: b * part,
                    body: plan.bodies.len() as u32,
                });
                plan.bodies.push(RigidMotion {
                    velocity: [0.01 * (x + s) as f64 - 0.1, 0.005 * y as f64 - 0.02],
                    omega: 0.002 * (s as f64 - 0.5),
                    centre: [x as f64 - 3.0, y as f64 + 2.5],
                });
            }
            plan.total.push(b);
            plan.start.push(plan.shares.len() as u32);
        }
    }
    plan.rows.push(plan.cells.len() as u32);
    plan
}

/// The two lattices' fluid cells hold the same bits (the first difference named).
fn same_fields<T: Real>(a: &Lattice<T>, b: &Lattice<T>, what: &str) {
    let (nx, ny) = (a.nx(), a.ny());
    let (ea, eb) = (a.export_interior(), b.export_interior());
    for (at, (u, v)) in ea.iter().zip(&eb).enumerate() {
        let (i, y, x) = (at / (nx * ny), at / nx % ny, at % nx);
        if !obstacle(x, y) && u.to_f64().to_bits() != v.to_f64().to_bits() {
            panic!("{what}: cell ({x}, {y}) direction {i}: {u:?} vs {v:?}");
        }
    }
}

/// A lattice built with one buffer takes the same initial conditions and, in place, the
/// same steps as one built with two, in half the storage.
#[test]
fn one_buffer_lattices_step_in_place_as_two_buffer_ones() {
    let (mut one, mut two) = (
        lattice_with::<f64>(Collision::Bgk, 1),
        lattice_with::<f64>(Collision::Bgk, 2),
    );
    assert_eq!(2 * one.storage_bytes(), two.storage_bytes());
    one.make_in_place();
    two.make_in_place();
    assert_eq!(one.storage_bytes(), two.storage_bytes());
    for _ in 0..5 {
        one.step().unwrap();
        two.step().unwrap();
    }
    same_fields(&one, &two, "one buffer against two, in place");
    // A checkpoint imported before going in place, as a restart does.
    let state = two.export_interior();
    let (mut one, mut two) = (
        lattice_with::<f64>(Collision::Bgk, 1),
        lattice_with::<f64>(Collision::Bgk, 2),
    );
    for lat in [&mut one, &mut two] {
        lat.import_interior(&state, 5, &SingleProcess);
        lat.make_in_place();
        lat.step().unwrap();
    }
    same_fields(&one, &two, "one buffer against two, from a checkpoint");
}

/// A lattice built with one buffer refuses the two-array step.
#[test]
#[should_panic(expected = "steps in place only")]
fn one_buffer_lattices_refuse_the_two_array_step() {
    let _ = lattice_with::<f64>(Collision::Bgk, 1).step();
}

/// The in-place sweep's wall runs (the rows along the south and north walls, taken in
/// lanes) give the two-array kernel's values and wall forces (its scalar path) bit for bit,
/// with a moving wall, in f32 and f64.
#[test]
fn wall_runs_match_the_scalar_path() {
    fn check<T: Real>() {
        let (mut lanes, mut scalar) = (lattice::<T>(Collision::Bgk), lattice::<T>(Collision::Bgk));
        for lat in [&mut lanes, &mut scalar] {
            lat.solids[0].velocity = [0.03, -0.01];
        }
        // Row 0: one run of every cell but the corners, several chunks and a remainder.
        assert_eq!(lanes.plan[0].wall_runs, vec![(1, 59)]);
        lanes.make_in_place();
        for step in 0..4 {
            lanes.step().unwrap();
            scalar.step().unwrap();
            same_fields(&lanes, &scalar, &format!("wall runs, step {step}"));
            let (a, b) = (lanes.forces(&SingleProcess), scalar.forces(&SingleProcess));
            let bits =
                |f: &[[f64; 2]]| -> Vec<u64> { f.iter().flatten().map(|v| v.to_bits()).collect() };
            assert_eq!(
                bits(&a),
                bits(&b),
                "wall forces, step {step}: {a:?} vs {b:?}"
            );
        }
    }
    check::<f32>();
    check::<f64>();
}

fn bits<T: Real>(v: &[T]) -> Vec<u64> {
    v.iter().map(|x| x.to_f64().to_bits()).collect()
}

/// The in-place sweep computes the partially saturated cells inside its bulk runs and
/// special cells, on push and local steps: the same bits, fields and momenta, as the
/// two-array kernel, which computes them one by one after its sweep.
fn in_place_partial_cells_match_two_arrays<T: Real>(collision: Collision) {
    let mut two = lattice::<T>(collision);
    let mut one = lattice::<T>(collision);
    one.make_in_place();
    let plan = plan(&two);
    assert!(plan.cells.len() > 150);
    let (mut m2, mut m1) = (Vec::new(), Vec::new());
    for step in 0..4 {
        for (lat, m) in [(&mut two, &mut m2), (&mut one, &mut m1)] {
            let bad = lat
                .stream_collide_moving(
                    &SingleProcess,
                    &mut MovingCells::Partial(&plan, m, &mut BodyColumns::default()),
                )
                .unwrap();
            assert!(bad.is_none());
            lat.update_boundaries();
        }
        same_fields(&two, &one, &format!("step {step}"));
        let flat = |m: &Vec<[f64; 2]>| m.iter().flatten().copied().collect::<Vec<_>>();
        assert_eq!(bits(&flat(&m2)), bits(&flat(&m1)), "step {step}");
        assert!(m1.iter().all(|p| p[0] != 0.0 || p[1] != 0.0));
    }
}

/// An empty plan (no rows at all) leaves the sweep as it is without one.
#[test]
fn an_empty_partial_plan_changes_nothing() {
    let mut with = lattice::<f64>(Collision::Bgk);
    let mut without = lattice::<f64>(Collision::Bgk);
    with.make_in_place();
    without.make_in_place();
    let (plan, mut m) = (PsmPlan::default(), Vec::new());
    for _ in 0..2 {
        with.stream_collide_moving(
            &SingleProcess,
            &mut MovingCells::Partial(&plan, &mut m, &mut BodyColumns::default()),
        )
        .unwrap();
        without
            .stream_collide_moving(&SingleProcess, &mut MovingCells::None)
            .unwrap();
        with.update_boundaries();
        without.update_boundaries();
    }
    same_fields(&with, &without, "empty plan");
}

/// The plan index of the cell the sweep reports bad, on two arrays and in place, after
/// one step in which only cell `n`'s solid moves at NaN.
fn bad_cell<T: Real>(n: usize) -> [Option<usize>; 2] {
    let mut plan = plan(&lattice::<T>(Collision::Bgk));
    // Each share has a body of its own: only this cell's shares go NaN.
    for at in plan.start[n]..plan.start[n + 1] {
        let body = plan.shares[at as usize].body as usize;
        plan.bodies[body].velocity = [f64::NAN, 0.0];
    }
    [false, true].map(|in_place| {
        let mut lat = lattice::<T>(Collision::Bgk);
        if in_place {
            lat.make_in_place();
        }
        let mut m = Vec::new();
        lat.stream_collide_moving(
            &SingleProcess,
            &mut MovingCells::Partial(&plan, &mut m, &mut BodyColumns::default()),
        )
        .unwrap()
        .map(|(bad, _)| bad)
    })
}

/// A cell that goes bad is named by its plan index, whichever lane of its chunk it
/// sits in and whether the chunk is blended as one grain's stretch or by share layer
/// (cells of two shares), in bulk runs and special cells, as the two-array kernel names it.
#[test]
fn in_place_partial_sweep_names_the_bad_cell() {
    let plan = plan(&lattice::<f32>(Collision::Bgk));
    let (mut one, mut two) = (0, 0);
    for n in (0..plan.cells.len()).step_by(3) {
        for got in [bad_cell::<f32>(n), bad_cell::<f64>(n)] {
            assert_eq!(got, [Some(n); 2], "plan cell {n}");
        }
        if plan.start[n + 1] - plan.start[n] == 1 {
            one += 1;
        } else {
            two += 1;
        }
    }
    assert!(
        one > 40 && two > 3,
        "{one} one-share and {two} two-share cells"
    );
}

#[test]
fn in_place_partial_cells_give_the_two_array_bits() {
    in_place_partial_cells_match_two_arrays::<f64>(Collision::Bgk);
    in_place_partial_cells_match_two_arrays::<f32>(Collision::Bgk);
    for collision in [
        Collision::Mrt {
            s_e: 1.2,
            s_eps: 1.5,
            s_q: None,
        },
        Collision::Trt { magic: 0.25 },
    ] {
        in_place_partial_cells_match_two_arrays::<f64>(collision);
        in_place_partial_cells_match_two_arrays::<f32>(collision);
    }
}

/// [`plan`] with its shares regrouped into bodies of 5 × 3 cells (a two-share cell's
/// second share on the body to its right), so that bodies span several rows and columns,
/// and each body's box (the cells of its shares) and one group per body.
fn grouped_plan<T: Real>(lat: &Lattice<T>) -> (PsmPlan, BodyColumns) {
    let mut plan = plan(lat);
    let per_row = lat.nx().div_ceil(5) + 1;
    let body = |x: usize, y: usize, s: usize| (y / 3) * per_row + x / 5 + s;
    let bodies = per_row * lat.ny().div_ceil(3);
    let mut boxes = vec![[u32::MAX, 0, u32::MAX, 0]; bodies];
    let mut ends = vec![[0u32; 2]; bodies];
    for n in 0..plan.cells.len() {
        let k = plan.cells[n] as usize;
        let y = PsmPlan::row_of(lat.stride, k);
        let x = k - (y + 1) * lat.stride - 1;
        for (s, at) in (plan.start[n]..plan.start[n + 1]).enumerate() {
            let b = body(x, y, s);
            plan.shares[at as usize].body = b as u32;
            let bx = &mut boxes[b];
            (bx[0], bx[2]) = (bx[0].min(x as u32), bx[2].min(y as u32));
            ends[b] = [ends[b][0].max(x as u32 + 1), ends[b][1].max(y as u32 + 1)];
        }
    }
    plan.bodies = (0..bodies)
        .map(|b| RigidMotion {
            velocity: [0.002 * (b % 7) as f64 - 0.006, 0.001 * (b % 5) as f64],
            omega: 0.001 * (b % 3) as f64 - 0.001,
            centre: [
                5.0 * (b % per_row) as f64 + 2.5,
                3.0 * (b / per_row) as f64 + 1.5,
            ],
        })
        .collect();
    let mut cols = BodyColumns::default();
    for (bx, e) in boxes.iter_mut().zip(&ends) {
        *bx = if bx[0] == u32::MAX {
            [0; 4]
        } else {
            [bx[0], e[0] - bx[0], bx[2], e[1] - bx[2]]
        };
    }
    cols.boxes = boxes;
    cols.members = (0..bodies as u32).collect();
    cols.groups = (0..=bodies as u32).collect();
    cols.first = vec![0];
    for b in 0..bodies {
        let next = cols.first[b] + cols.boxes[b][1];
        cols.first.push(next);
    }
    (plan, cols)
}

/// `cols` with body `pair.1` moved into `pair.0`'s group (they span the same columns).
fn join(cols: &mut BodyColumns, pair: (u32, u32)) {
    let mut members: Vec<u32> = cols
        .members
        .iter()
        .copied()
        .filter(|&b| b != pair.1)
        .collect();
    let at = members.iter().position(|&b| b == pair.0).expect("a member") + 1;
    members.insert(at, pair.1);
    let (mut groups, mut first) = (vec![0u32], vec![0u32]);
    let mut m = 0;
    while m < members.len() {
        let n = if members[m] == pair.0 { 2 } else { 1 };
        let width = cols.boxes[members[m] as usize][1];
        m += n;
        groups.push(m as u32);
        first.push(first.last().expect("one") + width);
    }
    (cols.members, cols.groups, cols.first) = (members, groups, first);
}

/// The in-place sweep by blocks of rows sums the loads of the bodies inside one block
/// itself, with the bits of the host's serial collect of the two-array kernel's momenta
/// (each column's cells in increasing row, a cell's shares in plan order), and reports one
/// momentum per share, the two-array kernel's, for the bodies across blocks.
fn in_place_sums_match_the_serial_collect<T: Real>() {
    let mut two = lattice::<T>(Collision::Bgk);
    let mut one = lattice::<T>(Collision::Bgk);
    one.make_in_place();
    let (plan, mut wanted) = grouped_plan(&two);
    // A body of the first block and one of the last made one group (as a grain's images
    // across a periodic y face are), their boxes widened to the same columns: a group of
    // two is left to the host.
    let pair = {
        let bx = &mut wanted.boxes;
        let b1 = (0..bx.len())
            .find(|&b| bx[b][1] > 0 && bx[b][2] == 0)
            .expect("a body");
        let b2 = (0..bx.len())
            .find(|&b| bx[b][1] > 0 && bx[b][2] >= 6)
            .expect("a body");
        let lo = bx[b1][0].min(bx[b2][0]);
        let hi = (bx[b1][0] + bx[b1][1]).max(bx[b2][0] + bx[b2][1]);
        for b in [b1, b2] {
            bx[b][..2].copy_from_slice(&[lo, hi - lo]);
        }
        (b1 as u32, b2 as u32)
    };
    join(&mut wanted, pair);
    let (mut m2, mut m1) = (Vec::new(), Vec::new());
    let (stride, x0) = (two.stride, plan.x0);
    for step in 0..3 {
        let mut cols = wanted.clone();
        two.stream_collide_moving(
            &SingleProcess,
            &mut MovingCells::Partial(&plan, &mut m2, &mut BodyColumns::default()),
        )
        .unwrap();
        one.stream_collide_moving(
            &SingleProcess,
            &mut MovingCells::Partial(&plan, &mut m1, &mut cols),
        )
        .unwrap();
        assert!(cols.made, "step {step}: no sums");
        // The serial collect of the two-array momenta, per body and column.
        let mut want = vec![([0.0f64; 3], 0u32); cols.slots()];
        let (mut summed, mut reported) = (0, 0);
        for n in 0..plan.cells.len() {
            let k = plan.cells[n] as usize;
            let y = PsmPlan::row_of(stride, k);
            let x = k - (y + 1) * stride - 1;
            for s in plan.start[n] as usize..plan.start[n + 1] as usize {
                let b = plan.shares[s].body as usize;
                let slot = cols.body_slot[b];
                if slot == NO_SLOT {
                    assert_eq!(bits(&m1[s]), bits(&m2[s]), "step {step}: share {s}");
                    reported += 1;
                    continue;
                }
                let (p, c) = (m2[s], plan.bodies[b].centre);
                let centre = cell_centre(stride, x0, k, y);
                let arm = [centre[0] - c[0], centre[1] - c[1]];
                let load = [p[0], p[1], arm[0] * p[1] - arm[1] * p[0]];
                let (sum, count) = &mut want[(slot + x as i64) as usize];
                for a in 0..3 {
                    sum[a] = if *count == 0 {
                        0.0 + load[a]
                    } else {
                        sum[a] + load[a]
                    };
                }
                *count += 1;
                summed += 1;
            }
        }
        assert!(
            summed > 50 && reported > 50,
            "{summed} summed, {reported} reported"
        );
        assert_eq!(
            [
                cols.body_slot[pair.0 as usize],
                cols.body_slot[pair.1 as usize]
            ],
            [NO_SLOT; 2],
            "a group of two bodies"
        );
        for (slot, (sum, count)) in want.iter().enumerate() {
            assert_eq!(cols.counts[slot], *count, "step {step}: slot {slot}");
            if *count > 0 {
                assert_eq!(
                    bits(&cols.sums[slot]),
                    bits(sum),
                    "step {step}: slot {slot}"
                );
            }
        }
        two.update_boundaries();
        one.update_boundaries();
        same_fields(&two, &one, &format!("step {step}"));
    }
}

#[test]
fn in_place_sums_per_body_match_the_serial_collect() {
    in_place_sums_match_the_serial_collect::<f64>();
    in_place_sums_match_the_serial_collect::<f32>();
}
