//! The slide under force in MuJoCo: part A pressed on part B, moved along a line, drops in
//! where the line passes within the fit's clearance of the hole, and not where it passes
//! farther off, on every committed scene.

mod common;

use harness::sim::MAX_TIME;
use harness::world::World;

#[test]
fn a_slide_drops_in_where_it_crosses_the_hole_and_not_beside_it() {
    let (task, mut sim) = common::peg();
    let c = task.geometry().expect("a [geometry]").clearance();
    // Part B 0.2 mm off along +x; slides along x from 0.4 mm before it to 0.4 mm beyond.
    let hole = [0.0002, 0.0];
    sim.set_object(hole);
    for (beside, inserts) in [
        (0.0, true),
        (0.5 * c, true),
        (1.5 * c, false),
        (3.0 * c, false),
    ] {
        let from = [hole[0] - 0.0004, hole[1] + beside];
        let to = [hole[0] + 0.0004, hole[1] + beside];
        let slid = sim.slide_motion(from, to, to);
        let m = slid.end;
        assert!(m.settled, "{beside}: {m:?}");
        assert_eq!(
            m.inserted, inserts,
            "a slide {beside} m beside the hole: {m:?}"
        );
        if inserts {
            // It stopped where it dropped in: within the clearance of the hole.
            let off = (m.tcp[0] - hole[0]).hypot(m.tcp[1] - hole[1]);
            assert!(off < c, "{beside}: {m:?}");
            // And says so: it stopped short of its far end, where part A dropped.
            let [sx, sy] = slid.stopped;
            assert!((sx - hole[0]).hypot(sy - hole[1]) < c, "{beside}: {slid:?}");
        } else {
            // It ran to its end, and reads the static contact there, not the friction that
            // held part A sideways while it slid (15 N, 0.9 N.m about the sensor).
            assert!((m.tcp[0] - to[0]).abs() < 2e-5, "{beside}: {m:?}");
            assert_eq!(slid.stopped, to, "{beside}");
            // Ended as its speed settled, not by its torque (which static friction keeps
            // drifting to `sim::MAX_TIME`): the press, 0.16 s of sliding and the fresh
            // press take about 0.3 s of simulated time.
            assert!(m.time < 0.5 * MAX_TIME, "{beside}: {m:?}");
            let end = sim.contact_motion([m.tcp[0], m.tcp[1]]);
            for (x, y) in m.raw.iter().zip(&end.raw) {
                assert!((x - y).abs() < 1e-4, "{beside}: {m:?} {end:?}");
            }
            assert!(m.raw[0].hypot(m.raw[1]) < 0.1, "{beside}: {m:?}");
            // It read the press it started from at rest, as a contact motion there reads it,
            // and, told to press again halfway, reads the static contact there.
            let start = slid.start.expect("the press the slide started from");
            let there = sim.contact_motion(from);
            for (x, y) in start.raw.iter().zip(&there.raw) {
                assert!((x - y).abs() < 1e-4, "{beside}: {start:?} {there:?}");
            }
            let mid = [hole[0], hole[1] + beside];
            let pressed = sim.slide_motion(from, to, mid).end;
            let there = sim.contact_motion(mid);
            assert!(
                (pressed.tcp[0] - mid[0]).abs() < 2e-5,
                "{beside}: {pressed:?}"
            );
            for (x, y) in pressed.raw.iter().zip(&there.raw) {
                assert!((x - y).abs() < 1e-4, "{beside}: {pressed:?} {there:?}");
            }
        }
    }
    // A slide of no length reads what a contact motion reads (it settles twice).
    let a = sim
        .slide_motion([0.001, 0.0], [0.001, 0.0], [0.001, 0.0])
        .end;
    let b = sim.contact_motion([0.001, 0.0]);
    for (x, y) in a.raw.iter().zip(&b.raw) {
        assert!((x - y).abs() < 1e-4, "{a:?} {b:?}");
    }
}

#[test]
fn on_every_scene_a_slide_drops_in_within_the_clearance_and_not_beyond() {
    // The FMU rules out part B within the fit's clearance of a slide's line that did not go
    // in (inputs `slide`, `slide_start.*`): a slide passing 0.9 clearances beside the hole
    // must drop in on every committed scene, one 1.5 clearances beside it must not.
    for name in [
        "peg_in_hole",
        "tight_peg",
        "octagon",
        "gear",
        "bearing_housing",
    ] {
        let (task, mut sim) = common::scene(name);
        let c = task.geometry().expect("a [geometry]").clearance();
        let hole = [0.0002, 0.0];
        sim.set_object(hole);
        for (beside, inserts) in [(0.9 * c, true), (1.5 * c, false)] {
            let from = [hole[0] - 0.0004, hole[1] + beside];
            let to = [hole[0] + 0.0004, hole[1] + beside];
            let m = sim.slide_motion(from, to, to).end;
            assert_eq!(
                m.inserted, inserts,
                "{name}: a slide {beside} m beside the hole: {m:?}"
            );
        }
    }
}
