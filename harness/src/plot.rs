//! Plots a person looks at (PNG): the estimate after the first measurements of a trial (the
//! paper's Fig. 8, and Fig. 12 with a camera: the estimate and its 1- and 2-sigma
//! ellipses), the particles themselves from the FMU's trace (Fig. 8 and 9, a panel per
//! pair of DOFs), contacts per trial of two campaigns, contacts per true offset of a sweep
//! (Fig. 10), and the agreement of two maps.

use std::path::Path;

use plotters::prelude::*;

use crate::error::{HarnessError, Result, create_parent};
use crate::fmu_driver::Estimate;
use crate::report::{self, TrialRow};
use crate::trial::TrialResult;
use model_description::trace::TraceMeasurement;

type Draw = std::result::Result<(), Box<dyn std::error::Error + Send + Sync>>;

fn wrap(path: &Path, r: Draw) -> Result<()> {
    r.map_err(|e| HarnessError::plot(path, e))
}

/// Estimate and spread after the first three measurements of `trial` (an image before the
/// first contact, where a camera took part, then contacts) over Omega (±`size` m).
///
/// # Errors
/// When the image cannot be written.
pub fn estimates(path: &Path, trial: &TrialResult, size: f64) -> Result<()> {
    create_parent(path)?;
    wrap(path, draw_estimates(path, trial, size))
}

/// One panel: its caption, the contact points so far and the estimate shown.
struct Panel {
    caption: String,
    tcps: Vec<(f64, f64)>,
    estimate: Option<Estimate>,
}

/// The first three measurements of a trial as panels.
fn panels(trial: &TrialResult) -> Vec<Panel> {
    let mut out: Vec<Panel> = trial
        .first_look
        .iter()
        .map(|e| Panel {
            caption: "after the first image (no contact)".into(),
            tcps: Vec::new(),
            estimate: Some(*e),
        })
        .collect();
    for (k, st) in trial.steps.iter().enumerate() {
        let caption = match (st.estimate, st.image) {
            (Some(_), true) => format!("after contact {} + image", k + 1),
            (Some(_), false) => format!("after contact {}", k + 1),
            (None, _) => format!("contact {}: inserted", k + 1),
        };
        let tcps = trial.steps[..=k]
            .iter()
            .map(|s| (s.tcp[0] * 1e3, s.tcp[1] * 1e3))
            .collect();
        out.push(Panel {
            caption,
            tcps,
            estimate: st.estimate,
        });
    }
    out.truncate(3);
    while out.len() < 3 {
        out.push(Panel {
            caption: "none (done)".into(),
            tcps: Vec::new(),
            estimate: None,
        });
    }
    out
}

fn draw_estimates(path: &Path, trial: &TrialResult, size: f64) -> Draw {
    let root = BitMapBackend::new(path, (1500, 1040)).into_drawing_area();
    root.fill(&WHITE)?;
    let areas = root.split_evenly((2, 3));
    let panels = panels(trial);
    let truth = (trial.offset[0] * 1e3, trial.offset[1] * 1e3);
    // Top row: Omega; bottom row: about the true offset, wide enough for every 2-sigma ellipse.
    let spread = panels
        .iter()
        .filter_map(|p| p.estimate)
        .map(|e| {
            2.0 * e.std[0].max(e.std[1])
                + (e.object[0] - trial.offset[0]).hypot(e.object[1] - trial.offset[1])
        })
        .fold(0.0, f64::max);
    let zoom = (1.2 * spread).clamp(2.5e-4, size) * 1e3;
    let s = size * 1e3;
    for (k, area) in areas.iter().enumerate() {
        let panel = &panels[k % 3];
        let (xr, yr, caption) = if k < 3 {
            (-s..s, -s..s, panel.caption.clone())
        } else {
            (
                (truth.0 - zoom)..(truth.0 + zoom),
                (truth.1 - zoom)..(truth.1 + zoom),
                format!("{} (zoom)", panel.caption),
            )
        };
        let shown: Vec<(f64, f64)> = panel
            .tcps
            .iter()
            .copied()
            .filter(|p| xr.contains(&p.0) && yr.contains(&p.1))
            .collect();
        let mut chart = ChartBuilder::on(area)
            .caption(caption, ("sans-serif", 20))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(55)
            .build_cartesian_2d(xr, yr)?;
        chart
            .configure_mesh()
            .x_desc("object.x [mm]")
            .y_desc("object.y [mm]")
            .draw()?;
        chart
            .draw_series(std::iter::once(Cross::new(truth, 9, RED.stroke_width(3))))?
            .label("true offset")
            .legend(|(x, y)| Cross::new((x, y), 5, RED.stroke_width(2)));
        chart
            .draw_series(
                shown
                    .iter()
                    .map(|p| TriangleMarker::new(*p, 7, BLACK.filled())),
            )?
            .label("contact points")
            .legend(|(x, y)| TriangleMarker::new((x, y), 5, BLACK.filled()));
        if let Some(e) = panel.estimate {
            let (cx, cy) = (e.object[0] * 1e3, e.object[1] * 1e3);
            for (n, colour) in [(1.0, BLUE.mix(1.0)), (2.0, BLUE.mix(0.4))] {
                let ring: Vec<(f64, f64)> = (0..=72)
                    .map(|i| {
                        let t = std::f64::consts::TAU * i as f64 / 72.0;
                        (
                            cx + n * e.std[0] * 1e3 * t.cos(),
                            cy + n * e.std[1] * 1e3 * t.sin(),
                        )
                    })
                    .collect();
                chart.draw_series(LineSeries::new(ring, colour.stroke_width(2)))?;
            }
            chart
                .draw_series(std::iter::once(Circle::new((cx, cy), 5, BLUE.filled())))?
                .label(format!("estimate, 1/2 sigma (conf {:.2})", e.confidence))
                .legend(|(x, y)| Circle::new((x, y), 4, BLUE.filled()));
        }
        if k < 3 {
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .draw()?;
        }
    }
    root.present()?;
    Ok(())
}

/// The particles after each of `measurements` (the FMU's trace of one trial, its first
/// three used), a row per measurement and a panel per pair of DOFs (the paper's Fig. 8 and
/// 9), the particles' colour darker with their weight, the estimate and `truth` (one value
/// per DOF, m or rad) marked; translations in mm, rotations in degrees.
///
/// # Errors
/// When the image cannot be written or there is nothing to draw.
pub fn particles(path: &Path, measurements: &[TraceMeasurement], truth: &[f64]) -> Result<()> {
    create_parent(path)?;
    wrap(path, draw_particles(path, measurements, truth))
}

/// A DOF's value as plotted: mm or degrees ([`report::shown`]).
fn shown(dof: &str, v: f64) -> f64 {
    report::shown(dof, v).0
}

fn draw_particles(path: &Path, measurements: &[TraceMeasurement], truth: &[f64]) -> Draw {
    let rows = &measurements[..measurements.len().min(3)];
    let Some(first) = rows.first() else {
        return Err("the trace holds no measurement".into());
    };
    let d = first.dofs.len();
    let pairs: Vec<(usize, usize)> = if d == 1 {
        vec![(0, 0)]
    } else {
        (0..d)
            .flat_map(|a| (a + 1..d).map(move |b| (a, b)))
            .collect()
    };
    let root = BitMapBackend::new(path, (480 * pairs.len() as u32, 440 * rows.len() as u32))
        .into_drawing_area();
    root.fill(&WHITE)?;
    let areas = root.split_evenly((rows.len(), pairs.len()));
    for (r, m) in rows.iter().enumerate() {
        let top = m
            .weights
            .iter()
            .copied()
            .fold(0.0, f64::max)
            .max(f64::MIN_POSITIVE);
        for (c, &(a, b)) in pairs.iter().enumerate() {
            let (na, nb) = (&m.dofs[a], &m.dofs[b]);
            let range = |k: usize, name: &str| {
                let (lo, hi) = m
                    .poses
                    .iter()
                    .map(|p| shown(name, p[k]))
                    .chain([shown(name, truth.get(k).copied().unwrap_or(0.0))])
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
                        (l.min(v), h.max(v))
                    });
                let pad = 0.05 * (hi - lo).max(1e-3);
                (lo - pad)..(hi + pad)
            };
            let mut chart = ChartBuilder::on(&areas[r * pairs.len() + c])
                .caption(
                    format!("after measurement {}: {na}, {nb}", m.measurement),
                    ("sans-serif", 18),
                )
                .margin(10)
                .x_label_area_size(40)
                .y_label_area_size(55)
                .build_cartesian_2d(range(a, na), range(b, nb))?;
            let unit = |n: &str| report::shown(n, 0.0).1;
            chart
                .configure_mesh()
                .x_desc(format!("{na} [{}]", unit(na)))
                .y_desc(format!("{nb} [{}]", unit(nb)))
                .draw()?;
            chart.draw_series(m.poses.iter().zip(&m.weights).map(|(p, w)| {
                let shade = 0.15 + 0.85 * (w / top);
                Circle::new(
                    (shown(na, p[a]), shown(nb, p[b])),
                    2,
                    BLUE.mix(shade).filled(),
                )
            }))?;
            let at = |v: &[f64]| (shown(na, v[a]), shown(nb, v[b]));
            chart.draw_series(std::iter::once(Circle::new(
                at(&m.estimate),
                6,
                BLACK.stroke_width(2),
            )))?;
            chart.draw_series(std::iter::once(Cross::new(
                at(truth),
                9,
                RED.stroke_width(3),
            )))?;
        }
    }
    root.present()?;
    Ok(())
}

/// Contact motions per trial of two campaigns (e.g. experiment D with and without vision).
///
/// # Errors
/// When the image cannot be written.
pub fn contacts_per_trial(path: &Path, names: [&str; 2], runs: [&[TrialRow]; 2]) -> Result<()> {
    create_parent(path)?;
    wrap(path, draw_contacts_per_trial(path, names, runs))
}

fn draw_contacts_per_trial(path: &Path, names: [&str; 2], runs: [&[TrialRow]; 2]) -> Draw {
    let root = BitMapBackend::new(path, (1000, 520)).into_drawing_area();
    root.fill(&WHITE)?;
    let n = runs[0].len().max(runs[1].len()).max(1);
    let top = runs
        .iter()
        .flat_map(|r| r.iter().map(|t| t.contacts))
        .max()
        .unwrap_or(1) as f64
        + 1.0;
    let mut chart = ChartBuilder::on(&root)
        .caption("contact motions per trial", ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(-0.5..n as f64 - 0.5, 0.0..top)?;
    chart
        .configure_mesh()
        .x_desc("trial")
        .y_desc("contacts")
        .draw()?;
    for (k, (name, run)) in names.iter().zip(runs).enumerate() {
        let colour = if k == 0 { BLUE } else { RED };
        let dx = if k == 0 { -0.15 } else { 0.15 };
        let mean = run.iter().map(|t| t.contacts as f64).sum::<f64>() / run.len().max(1) as f64;
        chart
            .draw_series(run.iter().enumerate().map(|(i, t)| {
                let style = if t.success {
                    colour.filled()
                } else {
                    BLACK.filled()
                };
                Rectangle::new(
                    [
                        (i as f64 + dx - 0.13, 0.0),
                        (i as f64 + dx + 0.13, t.contacts as f64),
                    ],
                    style,
                )
            }))?
            .label(format!("{name} (mean {mean:.2}; black: failed)"))
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 10, y + 5)], colour.filled()));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}

/// Contacts needed per true offset of a sweep (the paper's Fig. 10); failures in black.
///
/// # Errors
/// When the image cannot be written.
pub fn sweep(path: &Path, results: &[TrialResult], size: f64, cell: f64) -> Result<()> {
    create_parent(path)?;
    wrap(path, draw_sweep(path, results, size, cell))
}

fn draw_sweep(path: &Path, results: &[TrialResult], size: f64, cell: f64) -> Draw {
    let root = BitMapBackend::new(path, (820, 760)).into_drawing_area();
    root.fill(&WHITE)?;
    let (s, h) = ((size + cell / 2.0) * 1e3, cell * 1e3 / 2.0);
    let max = results
        .iter()
        .filter(|r| r.success)
        .map(|r| r.contacts)
        .max()
        .unwrap_or(1)
        .max(2) as f64;
    let mut chart = ChartBuilder::on(&root)
        .caption("contact motions per true offset", ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(55)
        .build_cartesian_2d(-s..s, -s..s)?;
    chart
        .configure_mesh()
        .x_desc("object.x [mm]")
        .y_desc("object.y [mm]")
        .disable_mesh()
        .draw()?;
    for r in results {
        let (x, y) = (r.offset[0] * 1e3, r.offset[1] * 1e3);
        let colour = if r.success {
            ViridisRGB::get_color((r.contacts as f64 - 1.0) / (max - 1.0))
        } else {
            BLACK
        };
        chart.draw_series(std::iter::once(Rectangle::new(
            [(x - h, y - h), (x + h, y + h)],
            colour.filled(),
        )))?;
        let label = if r.success {
            r.contacts.to_string()
        } else {
            "x".into()
        };
        let text_colour = if r.success && (r.contacts as f64) > 0.6 * max {
            BLACK
        } else {
            WHITE
        };
        chart.draw_series(std::iter::once(Text::new(
            label,
            (x - h * 0.3, y + h * 0.3),
            ("sans-serif", 14).into_font().color(&text_colour),
        )))?;
    }
    root.present()?;
    Ok(())
}

/// Scatter of two maps' values of the channels `names`, one panel each, with y = x, and a
/// last panel of `differences` (the torque difference at each cell's first two coordinates,
/// m, with those axes' names) over the map: where the maps disagree.
///
/// # Errors
/// When the image cannot be written.
pub fn agreement(
    path: &Path,
    names: &[&str],
    pairs: &[Vec<(f64, f64)>],
    labels: [&str; 2],
    differences: (&[([f64; 2], f64)], [&str; 2]),
) -> Result<()> {
    create_parent(path)?;
    wrap(
        path,
        draw_agreement(path, names, pairs, labels, differences),
    )
}

fn draw_agreement(
    path: &Path,
    names: &[&str],
    pairs: &[Vec<(f64, f64)>],
    labels: [&str; 2],
    differences: (&[([f64; 2], f64)], [&str; 2]),
) -> Draw {
    let n = names.len() + 1;
    let root = BitMapBackend::new(path, (520 * n as u32, 520)).into_drawing_area();
    root.fill(&WHITE)?;
    let panels = root.split_evenly((1, n));
    draw_differences(&panels[n - 1], differences.0, differences.1)?;
    for ((area, name), pts) in panels.iter().zip(names).zip(pairs) {
        let m = pts
            .iter()
            .flat_map(|p| [p.0.abs(), p.1.abs()])
            .fold(1e-9, f64::max)
            * 1.05;
        let mut chart = ChartBuilder::on(area)
            .caption(*name, ("sans-serif", 20))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(-m..m, -m..m)?;
        chart
            .configure_mesh()
            .x_desc(labels[0])
            .y_desc(labels[1])
            .draw()?;
        chart.draw_series(LineSeries::new([(-m, -m), (m, m)], BLACK.mix(0.5)))?;
        chart.draw_series(
            pts.iter()
                .map(|p| Circle::new(*p, 2, BLUE.mix(0.5).filled())),
        )?;
    }
    root.present()?;
    Ok(())
}

/// The torque difference over the map's first two axes (mm), one square per cell, darker
/// where the maps disagree more (scale: white 0 to black at the 99th percentile, so that a
/// few extreme cells do not wash out the rest).
fn draw_differences(
    area: &DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>,
    cells: &[([f64; 2], f64)],
    axes: [&str; 2],
) -> Draw {
    let (lo, hi) = cells.iter().fold(
        ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
        |(lo, hi), (at, _)| {
            (
                [lo[0].min(at[0]), lo[1].min(at[1])],
                [hi[0].max(at[0]), hi[1].max(at[1])],
            )
        },
    );
    if !(lo[0] < hi[0] && lo[1] < hi[1]) {
        return Ok(());
    }
    let mut sorted: Vec<f64> = cells
        .iter()
        .map(|c| c.1)
        .filter(|d| d.is_finite())
        .collect();
    sorted.sort_by(f64::total_cmp);
    let top = sorted
        .get((sorted.len() * 99 / 100).min(sorted.len().saturating_sub(1)))
        .copied()
        .unwrap_or(0.0)
        .max(1e-12);
    // Half a cell: the grid step estimated from the extent and the cell count.
    let side = (cells.len() as f64).sqrt().max(2.0) - 1.0;
    let half = [(hi[0] - lo[0]) / side / 2.0, (hi[1] - lo[1]) / side / 2.0];
    let mm = |v: f64| v * 1e3;
    let mut chart = ChartBuilder::on(area)
        .caption(
            format!("|torque B - A|, black >= {top:.3} N m"),
            ("sans-serif", 20),
        )
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(
            mm(lo[0] - half[0])..mm(hi[0] + half[0]),
            mm(lo[1] - half[1])..mm(hi[1] + half[1]),
        )?;
    chart
        .configure_mesh()
        .x_desc(format!("{} [mm]", axes[0]))
        .y_desc(format!("{} [mm]", axes[1]))
        .draw()?;
    chart.draw_series(cells.iter().map(|(at, d)| {
        let shade = (255.0 * (1.0 - d / top)).round().clamp(0.0, 255.0) as u8;
        Rectangle::new(
            [
                (mm(at[0] - half[0]), mm(at[1] - half[1])),
                (mm(at[0] + half[0]), mm(at[1] + half[1])),
            ],
            RGBColor(shade, shade, shade).filled(),
        )
    }))?;
    Ok(())
}
