//! A measured map (contact motions in MuJoCo) against the map computed from CAD.

mod common;

use harness::compare::{Region, compare};
use harness::scan::scan;

#[test]
fn a_scan_of_a_small_grid_agrees_in_sign_with_the_computed_map() {
    let (task, mut sim) = common::peg();
    let measured = scan(&mut sim, &task, 0.001, 0.003).unwrap();
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
