//! The simulated F/T sensor in the FT-Map's convention, against the map computed from CAD.

mod common;

use harness::sensor::map_wrench;
use harness::sim::SUCCESS_HEIGHT;
use harness::world::World;

#[test]
fn a_peg_pressed_on_the_plate_reads_plus_the_imposed_force() {
    let (task, mut sim) = common::peg();
    sim.set_object([0.003, 0.0]);
    let c = sim.contact_motion([0.0, 0.0]);
    let w = map_wrench(c.raw);
    assert!(c.settled);
    assert!((w[2] - task.contact.force).abs() < 0.05, "fz {}", w[2]);
    assert!(
        w[0].abs() < 0.05 && w[1].abs() < 0.05,
        "lateral force {w:?}"
    );
}

#[test]
fn the_peg_on_rim_torque_direction_follows_the_offset_in_8_directions() {
    let (_, mut sim) = common::peg();
    let map = common::computed_peg_map();
    for k in 0..8 {
        let angle = std::f64::consts::FRAC_PI_4 * k as f64;
        let off = [0.002 * angle.cos(), 0.002 * angle.sin()];
        sim.set_object(off);
        let c = sim.contact_motion([0.0, 0.0]);
        let w = map_wrench(c.raw);
        let m = map.interpolate(&off).unwrap();
        // z x offset: the direction the convention of docs/method.md gives.
        let expect = [-off[1], off[0]];
        let dir = |t: [f64; 2]| t[1].atan2(t[0]);
        let diff = |a: f64, b: f64| {
            ((a - b + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI)
                .abs()
        };
        let (sim_dir, map_dir) = (dir([w[3], w[4]]), dir([m[3], m[4]]));
        assert!(
            diff(sim_dir, dir(expect)) < 5f64.to_radians(),
            "offset {off:?}: torque {w:?} not along z x offset"
        );
        assert!(
            diff(sim_dir, map_dir) < 5f64.to_radians(),
            "offset {off:?}: sim {w:?} map {m:?}"
        );
        for i in [3, 4] {
            if m[i].abs() > 0.01 {
                assert_eq!(
                    w[i].signum(),
                    m[i].signum(),
                    "offset {off:?} channel {i}: sim {w:?} map {m:?}"
                );
            }
        }
        // The magnitude agrees with the pressure-centroid map within 10 %.
        let (ts, tm) = (w[3].hypot(w[4]), m[3].hypot(m[4]));
        assert!(
            (ts - tm).abs() < 0.1 * tm,
            "offset {off:?}: |t| sim {ts} map {tm}"
        );
        // tcp.z is the map's depth channel: the hole depth on the rim.
        assert!(
            (c.tcp[2] - m[6]).abs() < 1e-4,
            "offset {off:?}: tcp.z {} map depth {}",
            c.tcp[2],
            m[6]
        );
    }
}

#[test]
fn a_centred_peg_is_fed_in_to_the_success_height() {
    let (_, mut sim) = common::peg();
    sim.set_object([0.0, 0.0]);
    let c = sim.contact_motion([0.0, 0.0]);
    // The motion ends within a step's feed (20 µm) below the success height.
    assert!(
        c.settled && c.inserted && c.tcp[2] < SUCCESS_HEIGHT && c.tcp[2] > SUCCESS_HEIGHT - 3e-5,
        "tcp {:?}",
        c.tcp
    );
    // Inserted: no torque left.
    let w = map_wrench(c.raw);
    assert!(w[3].abs() < 1e-3 && w[4].abs() < 1e-3, "{w:?}");
}
