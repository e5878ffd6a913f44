//! A measured map (contact motions in MuJoCo) against the map computed from CAD.

mod common;

use harness::compare::{Region, compare};
use harness::scan::{Yaw, scan};

#[test]
fn a_scan_of_a_small_grid_agrees_in_sign_with_the_computed_map() {
    let (task, mut sim) = common::peg();
    let unturned = Yaw {
        step: 1.0,
        size: 0.0,
    };
    let measured = scan(&mut sim, &task, 0.001, 0.003, unturned).unwrap();
    assert_eq!(measured.grid().cells(), 49);
    assert_eq!(measured.meta().model, ftmap::WrenchModel::Measured);
    let a = compare(&measured, common::computed_peg_map()).unwrap();
    for ch in &a.channels[3..5] {
        assert!(ch.sign_agreement == 1.0, "{}: {}", ch.name, a.table());
        assert!(ch.correlation > 0.95, "{}: {}", ch.name, a.table());
    }
    assert!(a.torque_angle_max < 5f64.to_radians(), "{}", a.table());
    // Regions by the computed map: on this 1 mm grid over ±3 mm only the centred peg goes in
    // (0.05 mm clearance), and every other offset (at most 4.3 mm) puts the 9.9 mm peg over
    // the 10 mm hole's edge: no cell rests flat on the top face.
    let cells_in = |region| a.cells.iter().filter(|c| c.region == region).count();
    assert_eq!(
        [Region::Centre, Region::Rim, Region::Outside].map(cells_in),
        [1, 48, 0],
        "{}",
        a.table()
    );
    let centre = &a.regions[0];
    assert_eq!(
        (centre.region, centre.channels[3].cells),
        (Region::Centre, 1)
    );
    assert_eq!(a.axes, ["object.x", "object.y"]);
    // Round trip through the map file format.
    let dir = std::env::temp_dir().join(format!("harness-scan-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("measured.ftmap");
    ftmap::map::format::save(&measured, &path).unwrap();
    assert_eq!(ftmap::map::format::load(&path).unwrap(), measured);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_scan_over_the_yaw_reads_each_turned_cell_at_its_own_yaw() {
    // octagon_yaw: part B 0.2 mm off along x or y and turned by -6, 0 or +6 degrees rests on
    // wedges along the peg's flats and patches at its corners. Each cell is held against the
    // polygons' exact torque under uniform pressure (the map's centroid model) at the cell's
    // own yaw, and is nearer it than the cell of the opposite yaw: a scan that left part B
    // unturned, or turned it the other way, fails.
    let (task, mut sim) = common::scene("octagon_yaw");
    let [peg, hole] = common::octagon_flats(&task);
    let yaw = Yaw {
        step: 6f64.to_radians(),
        size: 6f64.to_radians(),
    };
    let measured = scan(&mut sim, &task, 0.0002, 0.0002, yaw).unwrap();
    let names: Vec<String> = (measured.grid().axes().iter())
        .map(|a| a.dof.to_string())
        .collect();
    assert_eq!(names, ["object.x", "object.y", "object.rz"]);
    assert_eq!(measured.grid().cells(), 27);
    let exact = |d: [f64; 2], yaw: f64| {
        ftfusion_testkit::octagon_rim_torque(peg, hole, d, yaw, task.contact.force)
    };
    let mut checked = 0;
    for cell in 0..measured.grid().cells() {
        let c = measured.grid().coords(cell);
        let (d, yaw) = ([c[0], c[1]], c[2]);
        // Off along one axis: the yaws' wedges differ.
        if (d[0] == 0.0) == (d[1] == 0.0) || yaw == 0.0 {
            continue;
        }
        let w = measured.cell(cell);
        let miss = |e: [f64; 2]| (f64::from(w[3]) - e[0]).hypot(f64::from(w[4]) - e[1]);
        let (own, mirrored) = (exact(d, yaw), exact(d, -yaw));
        let size = own[0].hypot(own[1]);
        assert!(
            miss(own) < 0.15 * size && miss(own) < miss(mirrored),
            "{d:?} at {yaw} rad: scanned {w:?}, the polygons {own:?}, at the opposite yaw {mirrored:?}"
        );
        checked += 1;
    }
    assert_eq!(checked, 8);
}
