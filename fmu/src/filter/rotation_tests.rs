//! Tests of the filter on a map with a periodic yaw axis (an 8-fold symmetric fit): map
//! coordinates under a turned TCP against the closed-form relative pose, the estimate of a
//! set that straddles the period's seam, and the negative contact's rotational play.

use std::path::Path;

use ftfusion_testkit::CLEARANCE;
use ftmap::{Axis, Dof, FtMap, Grid, GridAxis, MapMeta, Pose};

use super::negative::RULED_OUT;
use super::*;
/// Yaw step of the synthetic map (rad): 2.5 degrees, 18 steps per eighth of a turn.
const YAW_STEP: f64 = std::f64::consts::PI / 72.0;

/// A map over object x, y (±1 mm at 0.1 mm) and yaw (one period of an 8-fold symmetry):
/// a torque whose direction turns with the yaw, inserted within the clearance and two
/// yaw steps of zero (a play of one step: [`FtMap::rotational_play`]).
fn yaw_map() -> FtMap {
    let dof = |a| Dof::new(Pose::Object, a);
    let period = std::f64::consts::TAU / 8.0;
    let grid = Grid::new(vec![
        GridAxis::symmetric(dof(Axis::X), 1e-3, 1e-4).expect("x"),
        GridAxis::symmetric(dof(Axis::Y), 1e-3, 1e-4).expect("y"),
        GridAxis::symmetric(dof(Axis::Rz), period / 2.0, YAW_STEP).expect("rz"),
    ])
    .expect("grid");
    let meta = MapMeta {
        symmetry: Some(8),
        ..ftfusion_testkit::synthetic_meta("synthetic_yaw")
    };
    let mut map = FtMap::zeros(grid, meta);
    for cell in 0..map.grid().cells() {
        let c = map.grid().coords(cell);
        let inserted = c[0].hypot(c[1]) < CLEARANCE && c[2].abs() <= YAW_STEP * 2.01;
        let phase = 8.0 * c[2];
        *map.cell_mut(cell) = if inserted {
            [0.0; 7]
        } else {
            [
                0.0,
                0.0,
                50.0,
                (200.0 * c[1] + 0.05 * phase.cos()) as f32,
                (-200.0 * c[0] + 0.05 * phase.sin()) as f32,
                0.0,
                0.01,
            ]
        };
    }
    map
}

fn filter(particles: usize) -> Filter {
    Filter::new(
        &yaw_map(),
        Path::new("synthetic"),
        Config {
            particles,
            ..Config::default()
        },
    )
    .expect("filter")
}

/// `(x, y, yaw)` of particle `i` as grid coordinates.
fn place(f: &mut Filter, i: usize, pose: [f64; 3]) {
    let n = f.cfg.particles;
    for (k, v) in pose.iter().enumerate() {
        f.pos[k * n + i] = f.lookup.axes()[k].coord(*v);
    }
}

#[test]
fn the_yaw_axis_wraps_and_shows_the_fit_s_play() {
    let f = filter(10);
    let axes = f.lookup.axes();
    assert_eq!(axes[2].period, Some(18.0));
    assert_eq!((axes[0].period, axes[1].period), (None, None));
    // Inserted within two yaw steps of zero at zero offset: a play of one step.
    assert_eq!(f.lookup.play(), &[0.0, 0.0, 1.0]);
    assert!(f.negative_contact().is_some());
}

#[test]
fn map_coordinates_under_a_turned_tcp_are_the_relative_pose() {
    let mut f = filter(4);
    let poses = [
        [3e-4, -2e-4, 0.1],
        [-5e-4, 4e-4, -0.35],
        [1e-4, 1e-4, 0.38],
        [0.0, -6e-4, 0.0],
    ];
    for (i, p) in poses.iter().enumerate() {
        place(&mut f, i, *p);
    }
    let tcp = [1e-4, -1e-4, 0.01, 0.0, 0.0, 0.3];
    let mut rel = vec![0.0; 12];
    f.lookup.relative(&f.pos, &tcp, &mut rel, &mut Vec::new());
    let period = std::f64::consts::TAU / 8.0;
    for (i, p) in poses.iter().enumerate() {
        // The offset turned back by the TCP's yaw, the yaw's difference within half a period.
        let (dx, dy) = (p[0] - tcp[0], p[1] - tcp[1]);
        let (s, c) = tcp[5].sin_cos();
        let mut yaw = p[2] - tcp[5];
        yaw -= period * (yaw / period).round();
        let want = [c * dx + s * dy, -s * dx + c * dy, yaw];
        for (k, w) in want.iter().enumerate() {
            let got = f.lookup.axes()[k].value(rel[k * 4 + i]);
            assert!(
                (got - w).abs() < 1e-6,
                "particle {i}, axis {k}: {got} vs {w}"
            );
        }
    }
}

#[test]
fn a_set_straddling_the_seam_is_one_cluster_at_the_seam() {
    // Half the particles just below +22.5 degrees, half just above -22.5: one pose.
    let mut f = filter(1000);
    let half = std::f64::consts::PI / 8.0;
    for i in 0..1000 {
        let d = 0.01 * (i % 10) as f64 / 10.0;
        let yaw = if i % 2 == 0 { half - d } else { -half + d };
        place(&mut f, i, [2e-4, -3e-4, yaw]);
    }
    let e = Estimate::compute(&f.lookup, &f.cfg, &f.pos, &f.lw);
    assert_eq!(e.clusters, 1, "{e:?}");
    assert!(e.pose[2].abs() > half - 0.01, "{e:?}");
    assert!(e.std[2] < 0.01, "{e:?}");
    let s = spreads(f.lookup.axes(), &f.pos, &f.lw);
    assert!(f64::from(s[2]) * YAW_STEP < 0.01, "{s:?}");
}

#[test]
fn the_negative_contact_spares_the_particles_the_yaw_keeps_out() {
    let mut f = filter(4);
    let (yaw_in, yaw_out) = (0.5 * YAW_STEP, 1.5 * YAW_STEP);
    // Within the clearance at half the play: out where the offset is within the half
    // the play leaves; beyond the play: spared at any offset.
    for (i, p) in [
        [0.3 * CLEARANCE, 0.0, yaw_in],
        [0.7 * CLEARANCE, 0.0, yaw_in],
        [0.0, 0.0, yaw_out],
        [0.0, 0.2 * CLEARANCE, 0.0],
    ]
    .iter()
    .enumerate()
    {
        place(&mut f, i, *p);
    }
    let tcp = [0.0, 0.0, 0.01, 0.0, 0.0, 0.0];
    let mut rel = vec![0.0; 12];
    f.lookup.relative(&f.pos, &tcp, &mut rel, &mut Vec::new());
    let mut ll = vec![0.0; 4];
    let nc = f.negative_contact().expect("the term applies").clone();
    nc.add_log_likelihood(&f.pos, &rel, &[[[0.0; 3], [0.0; 3]]], &mut ll);
    let out: Vec<bool> = ll.iter().map(|l| *l < -1.0).collect();
    assert_eq!(out, [true, false, false, true], "{ll:?}");
}

#[test]
fn a_slide_and_a_press_off_its_line_rule_out_each_particle_once() {
    // A slide along y = 2 clearances, then a press at (0, -2) clearances: out, once each,
    // the particles within the clearance of the line or of the press; spared, one between.
    let mut f = filter(4);
    let c = CLEARANCE;
    for (i, p) in [
        [3.0 * c, 2.5 * c, 0.0],
        [0.2 * c, -2.0 * c, 0.0],
        [0.0, 0.0, 0.0],
        [-2.0 * c, 2.0 * c, 0.0],
    ]
    .iter()
    .enumerate()
    {
        place(&mut f, i, *p);
    }
    let tcp = [0.0, -2.0 * c, 0.01, 0.0, 0.0, 0.0];
    let mut rel = vec![0.0; 12];
    f.lookup.relative(&f.pos, &tcp, &mut rel, &mut Vec::new());
    let mut ll = vec![0.0; 4];
    let nc = f.negative_contact().expect("the term applies").clone();
    let (line, press) = (
        [[-4.0 * c, 2.0 * c, 0.0], [4.0 * c, 2.0 * c, 0.0]],
        [[0.0, -2.0 * c, 0.0]; 2],
    );
    nc.add_log_likelihood(&f.pos, &rel, &[line, press], &mut ll);
    assert_eq!(ll, [RULED_OUT, RULED_OUT, 0.0, RULED_OUT], "{ll:?}");
}

#[test]
fn a_twist_rules_out_the_yaws_it_passed_round_the_seam() {
    // A twist from 20 to 25 degrees crosses the seam at 22.5 (25 is -20 of the next
    // period). Particles at the TCP's x, y: out where their yaw lies on the way (or within
    // the play of it), spared elsewhere.
    let mut f = filter(5);
    let deg = f64::to_radians;
    let (start, end) = (deg(20.0), deg(25.0));
    let yaws = [deg(-22.0), deg(21.0), deg(0.0), deg(-18.5), deg(10.0)];
    for (i, y) in yaws.iter().enumerate() {
        place(&mut f, i, [0.0, 0.0, *y]);
    }
    let tcp = [0.0, 0.0, 0.01, 0.0, 0.0, end];
    let mut rel = vec![0.0; 15];
    f.lookup.relative(&f.pos, &tcp, &mut rel, &mut Vec::new());
    let mut ll = vec![0.0; 5];
    let nc = f.negative_contact().expect("the term applies").clone();
    nc.add_log_likelihood(
        &f.pos,
        &rel,
        &[[[0.0, 0.0, start], [0.0, 0.0, end]]],
        &mut ll,
    );
    let out: Vec<bool> = ll.iter().map(|l| *l < -1.0).collect();
    // -22 (= 23) and 21: passed; 0, 10: not; -18.5 (= 26.5): within the play (2.5
    // degrees) of the end.
    assert_eq!(out, [true, true, false, true, false], "{ll:?}");
    // Without the twist's start only the end's play counts: 23 and 21 are spared.
    let mut ll = vec![0.0; 5];
    nc.add_log_likelihood(&f.pos, &rel, &[[[0.0, 0.0, end], [0.0, 0.0, end]]], &mut ll);
    let out: Vec<bool> = ll.iter().map(|l| *l < -1.0).collect();
    assert_eq!(out, [true, false, false, true, false], "{ll:?}");
}

/// The synthetic map's measurement of part B at `truth` (x, y, yaw) from a TCP at `tcp`
/// (x, y, yaw): the map at the relative pose, the yaw's difference within half a period.
fn measured(map: &FtMap, truth: [f64; 3], tcp: [f64; 3]) -> Measurement {
    let (s, c) = tcp[2].sin_cos();
    let (dx, dy) = (truth[0] - tcp[0], truth[1] - tcp[1]);
    let period = std::f64::consts::TAU / 8.0;
    let mut yaw = truth[2] - tcp[2];
    yaw -= period * (yaw / period).round();
    let m = map
        .interpolate(&[c * dx + s * dy, -s * dx + c * dy, yaw])
        .expect("inside the map");
    Measurement {
        wrench: [m[0], m[1], m[2], m[3], m[4], m[5]],
        tcp: [tcp[0], tcp[1], m[6], 0.0, 0.0, tcp[2]],
        ..Measurement::default()
    }
}

#[test]
fn the_filter_recovers_a_known_yaw_across_the_seam() {
    // Contacts from turned TCPs; the yaw 22 degrees (and -22.4: near the seam either way).
    let map = yaw_map();
    for yaw in [22f64.to_radians(), -22.4f64.to_radians(), 0.12] {
        let truth = [3e-4, -2e-4, yaw];
        let mut f = Filter::new(
            &map,
            Path::new("synthetic"),
            Config {
                particles: 4000,
                ..Config::default()
            },
        )
        .expect("filter");
        for tcp in [[0.0, 0.0, 0.0], [-4e-4, 2e-4, 0.2], [5e-4, 4e-4, -0.3]] {
            f.measure(&measured(&map, truth, tcp)).expect("finite");
        }
        let e = f.estimate();
        let period = std::f64::consts::TAU / 8.0;
        let mut err = e.pose[2] - yaw;
        err -= period * (err / period).round();
        assert!(err.abs() < YAW_STEP, "yaw {yaw}: estimate {e:?}");
        assert!(
            (e.pose[0] - truth[0]).hypot(e.pose[1] - truth[1]) < 1e-4,
            "yaw {yaw}: estimate {e:?}"
        );
    }
}

#[test]
fn a_tilted_tcp_reads_the_same_offset_anywhere_along_its_axis() {
    // The map's x, y lie across the tool's axis: a TCP further along that axis (at its
    // contact height) reads the same x, y; one moved across it does not.
    let mut f = filter(2);
    place(&mut f, 0, [3e-4, -2e-4, 0.1]);
    place(&mut f, 1, [-5e-4, 1e-4, -0.2]);
    let (rx, ry) = (0.03, -0.02);
    let axis =
        nalgebra::Rotation3::new(nalgebra::Vector3::new(rx, ry, 0.0)) * nalgebra::Vector3::z();
    let z = 0.01;
    let at = |tcp: [f64; 6]| {
        let mut rel = vec![0.0; 6];
        f.lookup.relative(&f.pos, &tcp, &mut rel, &mut Vec::new());
        rel
    };
    let low = at([1e-4, 2e-4, 0.0, rx, ry, 0.0]);
    let along = at([
        1e-4 + z * axis.x / axis.z,
        2e-4 + z * axis.y / axis.z,
        z,
        rx,
        ry,
        0.0,
    ]);
    let across = at([1e-4 + 1e-4, 2e-4, z, rx, ry, 0.0]);
    for k in 0..4 {
        assert!((low[k] - along[k]).abs() < 1e-4, "{low:?} {along:?}");
    }
    assert!((low[0] - across[0]).abs() > 0.5, "{low:?} {across:?}");
}

#[test]
fn a_tilted_tcp_s_particles_see_their_height_along_its_axis() {
    // Tilted about one axis, the object's origin lies at the closed-form height along the
    // tool's axis: beside the TCP by d across the tilt, h cos t - d sin t (about y) or
    // h cos t + d sin t (about x); level or turned about the axis alone, every particle
    // sees the TCP's height.
    let mut f = filter(2);
    place(&mut f, 0, [3e-4, -2e-4, 0.0]);
    place(&mut f, 1, [-2e-3, 1.5e-3, 0.0]);
    let (tcp_xy, h, t): ([f64; 2], f64, f64) = ([1e-4, 2e-4], 0.01, 0.035);
    let heights = |rot: [f64; 3]| {
        let mut rel = vec![0.0; 6];
        let mut heights = vec![1.0];
        let tcp = [tcp_xy[0], tcp_xy[1], h, rot[0], rot[1], rot[2]];
        f.lookup.relative(&f.pos, &tcp, &mut rel, &mut heights);
        heights
    };
    assert!(heights([0.0; 3]).is_empty());
    for got in heights([0.0, 0.0, 0.2]) {
        assert!(
            (f64::from(got) - h).abs() < 1e-9,
            "a turn about the axis: {got}"
        );
    }
    let poses = [[3e-4, -2e-4], [-2e-3, 1.5e-3]];
    let (s, c) = t.sin_cos();
    // (rotation, the offset's axis across it, the sign of its term)
    for (rot, k, sign) in [([0.0, t, 0.0], 0, -1.0), ([t, 0.0, 0.0], 1, 1.0)] {
        let got = heights(rot);
        assert_eq!(got.len(), 2);
        for (i, p) in poses.iter().enumerate() {
            let want = h * c + sign * (p[k] - tcp_xy[k]) * s;
            assert!(
                (f64::from(got[i]) - want).abs() < 2e-8,
                "{rot:?} particle {i}: {} vs {want}",
                got[i]
            );
        }
    }
    // 2 mm beside the TCP at 2 degrees the world's height misses by about 70 µm.
    assert!((f64::from(heights([0.0, t, 0.0])[1]) - h).abs() > 6e-5);
}

#[test]
fn a_tilted_tcp_s_axis_meets_the_goal_s_height_beside_it() {
    // Tilted by t about y at height h, the tool's axis (pointing down, -z turned) meets
    // z = 0 at x - h tan t; about x, at y + h tan t. Level or turned about the axis alone,
    // under the TCP itself.
    let f = filter(1);
    let (x, y, h, t): (f64, f64, f64, f64) = (1e-3, -2e-3, 0.01, 0.035);
    let foot = |rot: [f64; 3]| f.lookup.axis_foot(&[x, y, h, rot[0], rot[1], rot[2]]);
    assert_eq!(foot([0.0; 3]), [x, y]);
    assert_eq!(foot([0.0, 0.0, 0.3]), [x, y]);
    for (rot, want) in [
        ([0.0, t, 0.0], [x - h * t.tan(), y]),
        ([t, 0.0, 0.0], [x, y + h * t.tan()]),
    ] {
        let got = foot(rot);
        assert!(
            (got[0] - want[0]).abs() < 1e-12 && (got[1] - want[1]).abs() < 1e-12,
            "{rot:?}: {got:?} vs {want:?}"
        );
    }
}

#[test]
fn a_set_collapsed_on_a_yaw_still_moves_along_it_by_a_share_of_a_grid_step() {
    // Every particle on one pose: the jitter's floor moves x and y by a share of the fit's
    // clearance (in their grid steps) and the yaw by the same share of its own grid step,
    // not of the clearance read in radians (which froze the yaw: here 0.001 of a step).
    let n = 4000;
    let mut f = filter(n);
    for i in 0..n {
        place(&mut f, i, [2e-4, -1e-4, 0.05]);
    }
    let before = f.pos.clone();
    let mut moved = f.pos.clone();
    f.jitter(&mut moved);
    let rms = |k: usize| {
        let s: f64 = (0..n)
            .map(|i| f64::from(moved[k * n + i] - before[k * n + i]).powi(2))
            .sum();
        (s / n as f64).sqrt()
    };
    let share = JITTER_SPREAD / (f.cfg.iterations as f64).sqrt();
    let x_floor = share * CLEARANCE / 1e-4;
    for (k, floor) in [(0, x_floor), (1, x_floor), (2, share)] {
        assert!(
            (rms(k) / floor - 1.0).abs() < 0.05,
            "axis {k}: moved {} grid steps, floor {floor}",
            rms(k)
        );
    }
}
