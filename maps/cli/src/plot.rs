//! Heat maps of one channel over two axes of a map (like the paper's Fig. 3 and 4):
//! PNG with axes in mm or degrees, a colour bar and a title.

use std::path::Path;

use anyhow::{Result, bail};
use plotters::prelude::*;

use ftmap::map::{CHANNELS, FtMap, UNITS, channel_index};
use ftmap::task::omega::MAX_AXES;

/// A 2-D slice of one channel: values over two axes with the others fixed.
#[derive(Debug, Clone)]
struct Slice {
    /// Grid axes shown along x and y.
    axes: [usize; 2],
    /// Values, row-major with x fastest.
    values: Vec<f64>,
    /// Description of the fixed axes, e.g. `object.rx=0.00°`.
    fixed: String,
}

/// Cuts the slice of `channel` over the first two axes (or `axes`), other axes at the
/// samples nearest to the values in `at` (default 0).
fn slice(
    map: &FtMap,
    channel: &str,
    axes: Option<[usize; 2]>,
    at: &[(String, f64)],
) -> Result<Slice> {
    let ch = channel_index(channel)?;
    let grid = map.grid();
    if grid.ndim() < 2 {
        bail!("a heat map needs a grid of at least 2 axes");
    }
    let axes = axes.unwrap_or([0, 1]);
    let mut idx = [0usize; MAX_AXES];
    let mut fixed = Vec::new();
    for (k, a) in grid.axes().iter().enumerate() {
        if axes.contains(&k) {
            continue;
        }
        let want = at
            .iter()
            .find(|(n, _)| *n == a.dof.to_string() || *n == a.dof.axis.name())
            .map_or(0.0, |(_, v)| *v);
        idx[k] = a.nearest(want);
        fixed.push(format!("{}={}", a.dof, a.dof.display(a.value(idx[k]))));
    }
    for (name, _) in at {
        if !grid
            .axes()
            .iter()
            .any(|a| a.dof.to_string() == *name || a.dof.axis.name() == name)
        {
            bail!("--at {name}: the map has no such axis");
        }
    }
    let (ax, ay) = (grid.axes()[axes[0]], grid.axes()[axes[1]]);
    let mut values = Vec::with_capacity(ax.count * ay.count);
    for j in 0..ay.count {
        for i in 0..ax.count {
            idx[axes[0]] = i;
            idx[axes[1]] = j;
            values.push(f64::from(map.cell(grid.flat(&idx[..grid.ndim()]))[ch]));
        }
    }
    Ok(Slice {
        axes,
        values,
        fixed: fixed.join(", "),
    })
}

/// Blue-white-red for signed channels, so that zero is white.
fn diverging(t: f64) -> RGBColor {
    let t = t.clamp(0.0, 1.0);
    let lerp = |a: f64, b: f64, s: f64| (a + (b - a) * s).round() as u8;
    if t < 0.5 {
        let s = t / 0.5;
        RGBColor(
            lerp(33.0, 255.0, s),
            lerp(102.0, 255.0, s),
            lerp(172.0, 255.0, s),
        )
    } else {
        let s = (t - 0.5) / 0.5;
        RGBColor(
            lerp(255.0, 178.0, s),
            lerp(255.0, 24.0, s),
            lerp(255.0, 43.0, s),
        )
    }
}

/// Writes the heat map of `channel` to a PNG file.
pub fn heat_map(
    map: &FtMap,
    channel: &str,
    axes: Option<[usize; 2]>,
    at: &[(String, f64)],
    out: &Path,
) -> Result<()> {
    let s = slice(map, channel, axes, at)?;
    draw(map, channel, &s, out).map_err(|e| anyhow::anyhow!("{}: {e}", out.display()))
}

fn draw(
    map: &FtMap,
    channel: &str,
    s: &Slice,
    out: &Path,
) -> std::result::Result<(), Box<dyn std::error::Error>> {
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    let grid = map.grid();
    let (ax, ay) = (grid.axes()[s.axes[0]], grid.axes()[s.axes[1]]);
    let ((sx, ux), (sy, uy)) = (ax.dof.display_unit(), ay.dof.display_unit());
    let finite = s.values.iter().copied().filter(|v| v.is_finite());
    let (lo, hi) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    let ch = channel_index(channel)?;
    let signed = ch < 6;
    let (lo, hi) = if signed {
        let m = lo.abs().max(hi.abs()).max(1e-12);
        (-m, m)
    } else if hi > lo {
        (lo, hi)
    } else {
        (lo - 1e-12, lo + 1e-12)
    };
    let colour = |v: f64| {
        let t = (v - lo) / (hi - lo);
        if signed {
            diverging(t)
        } else {
            ViridisRGB::get_color(t.clamp(0.0, 1.0))
        }
    };

    let root = BitMapBackend::new(out, (900, 760)).into_drawing_area();
    root.fill(&WHITE)?;
    let (main, bar) = root.split_horizontally(760);
    let title = format!(
        "{} [{}] of {} ({:?} model){}",
        CHANNELS[ch],
        UNITS[ch],
        map.meta().task,
        map.meta().model,
        if s.fixed.is_empty() {
            String::new()
        } else {
            format!(", {}", s.fixed)
        }
    );
    let (x0, x1) = (
        (ax.min - ax.step / 2.0) * sx,
        (ax.max() + ax.step / 2.0) * sx,
    );
    let (y0, y1) = (
        (ay.min - ay.step / 2.0) * sy,
        (ay.max() + ay.step / 2.0) * sy,
    );
    let mut chart = ChartBuilder::on(&main)
        .caption(title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(60)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .x_desc(format!("{} [{ux}]", ax.dof))
        .y_desc(format!("{} [{uy}]", ay.dof))
        .draw()?;
    chart.draw_series(
        (0..ay.count)
            .flat_map(|j| (0..ax.count).map(move |i| (i, j)))
            .map(|(i, j)| {
                let (cx, cy) = (ax.value(i) * sx, ay.value(j) * sy);
                let (hx, hy) = (ax.step * sx / 2.0, ay.step * sy / 2.0);
                let v = s.values[j * ax.count + i];
                let fill = if v.is_finite() {
                    colour(v).filled()
                } else {
                    BLACK.filled()
                };
                Rectangle::new([(cx - hx, cy - hy), (cx + hx, cy + hy)], fill)
            }),
    )?;

    let mut cb = ChartBuilder::on(&bar)
        .margin_top(40)
        .margin_bottom(57)
        .margin_right(10)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..1.0, lo..hi)?;
    cb.configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_label_style(("sans-serif", 14))
        .y_desc(UNITS[ch])
        .axis_desc_style(("sans-serif", 16))
        .draw()?;
    let n = 200;
    cb.draw_series((0..n).map(|k| {
        let (a, b) = (
            lo + (hi - lo) * k as f64 / n as f64,
            lo + (hi - lo) * (k + 1) as f64 / n as f64,
        );
        Rectangle::new([(0.0, a), (1.0, b)], colour((a + b) / 2.0).filled())
    }))?;
    root.present()?;
    Ok(())
}
