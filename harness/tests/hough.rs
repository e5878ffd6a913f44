//! The bounded Hough line detector on rendered images of the bearing housing scene
//! (experiment D): against the ground truth projected from the scene's geometry and against
//! the gradient detector of Fig. 5 (`detect_line`). An empty view: tests/vision.rs. Its
//! speed: `harness render --bench`.

mod common;

use std::sync::Mutex;

use harness::vision::features::{Detector, detect_edges_in};
use harness::vision::hough::{HoughParams, detect_line_hough};
use harness::vision::image::{Gradient, Line, LineParams, add_noise};

/// One offscreen GL context at a time.
static GL: Mutex<()> = Mutex::new(());

/// Angle (degrees) and offset (px) of `a` minus those of `b`, across the +-90 degree wrap
/// (where the normal, and so the offset's sign, flips).
fn diff(a: &Line, b: &Line) -> (f64, f64) {
    let da = a.angle - b.angle;
    if da > 90.0 {
        (da - 180.0, a.offset + b.offset)
    } else if da < -90.0 {
        (da + 180.0, a.offset + b.offset)
    } else {
        (da, a.offset - b.offset)
    }
}

#[test]
fn hough_edges_match_the_projected_geometry_and_detect_line() {
    let _gl = GL.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    let (task, mut view, model) = common::bearing();
    let cases = [
        ([0.0, 0.0], [0.0, 0.0]),
        ([0.002, -0.003], [0.0, 0.0]),
        ([-0.004, 0.0045], [0.0, 0.0]),
        ([0.001, 0.002], [0.0005, -0.001]),
    ];
    for (k, (object, tcp_xy)) in cases.iter().enumerate() {
        let tcp = [tcp_xy[0], tcp_xy[1], view.look_height()];
        view.place(*object, tcp);
        let image = view.render().expect("offscreen rendering (Mesa EGL)");
        let cam = view.camera();
        for noise in [None, Some(k as u64 + 1)] {
            let mut gray = image.to_gray();
            if let Some(seed) = noise {
                add_noise(&mut gray, 5.0, seed);
            }
            let grad = Gradient::sobel(cam.width, cam.height, &gray);
            // Expected endpoints, bands (the passive part's covers Omega), truth and detect_line's result.
            let results = detect_edges_in(
                &grad,
                &cam,
                &model,
                tcp,
                [object[0], object[1], 0.0],
                task.omega.size_trans,
                Detector::Gradient,
            );
            assert_eq!(results.len(), 4, "four edges expected");
            for r in &results {
                let ends = [r.expected.p0, r.expected.p1];
                let params = HoughParams {
                    line: LineParams {
                        band: r.band,
                        ..LineParams::default()
                    },
                    ..HoughParams::default()
                };
                let l = detect_line_hough(&grad, ends, &params).unwrap_or_else(|e| {
                    panic!("{} at object {object:?} (noise {noise:?}): {e}", r.name)
                });
                let g = r.found.as_ref().unwrap_or_else(|e| {
                    panic!("detect_line, {} at object {object:?}: {e}", r.name)
                });
                let (da, doff) = diff(&l, &r.truth);
                let (dga, dgoff) = diff(&l, g);
                println!(
                    "object {object:?} tcp {tcp_xy:?} noise {noise:?} {} (band {:.1} px): d_angle {da:.4} deg, d_offset {doff:.3} px; vs detect_line {dga:.4} deg, {dgoff:.3} px",
                    r.name, r.band
                );
                assert!(
                    da.abs() < 0.2,
                    "{} at {object:?} (noise {noise:?}): angle error {da} deg",
                    r.name
                );
                assert!(
                    doff.abs() < 0.5,
                    "{} at {object:?} (noise {noise:?}): offset error {doff} px",
                    r.name
                );
                assert!(
                    dgoff.abs() < 0.3,
                    "{} at {object:?} (noise {noise:?}): {dgoff} px from detect_line's {g:?}",
                    r.name
                );
            }
        }
    }
}
