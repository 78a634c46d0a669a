//! docs/accuracy.png: rolling error against cost, one point per configuration,
//! the Pareto front and the targets marked. Text is rendered with ab_glyph from
//! the DejaVu Sans font embedded by the `dejavu` crate: no system font library.

use std::path::Path;

use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};

use marble_rolling::study::{is_events, SceneId, BACKENDS, STEP_LOG2};

use super::report::{configs, firmware_k, label, per_second, sig, BUDGET_PER_MS, TARGET_MM};
use super::{Engine, Study, PEERS};

const FLOOR: f64 = 1e-6;

fn color(b: usize) -> RGBColor {
    [
        RGBColor(214, 39, 40),
        RGBColor(31, 119, 180),
        RGBColor(44, 160, 44),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(23, 190, 207),
    ][b % 6]
}

/// The peers' colours, in [`PEERS`] order.
fn peer_color(e: Engine) -> RGBColor {
    match e {
        Engine::Box2d => RGBColor(127, 127, 127),
        _ => RGBColor(255, 127, 14),
    }
}

fn bounds(v: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for x in v.filter(|x| x.is_finite() && *x > 0.0) {
        lo = lo.min(x);
        hi = hi.max(x);
    }
    if !lo.is_finite() {
        return (1.0, 10.0);
    }
    (lo / 2.0, hi * 2.0)
}

/// Draws the chart.
pub fn chart(study: &Study, path: &Path) -> Result<(), String> {
    register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular()).map_err(|_| "font")?;
    let configs = configs(study);
    let root = BitMapBackend::new(path, (1600, 760)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let (left, right) = root.split_horizontally(800);
    let err = |e: f64| e.max(FLOOR);

    // Left: target cost.
    let have_m4 = configs.iter().any(|c| c.m4_ms.is_some());
    let (x0, x1) = bounds(configs.iter().map(|c| c.cost()).chain([BUDGET_PER_MS]));
    let (y0, y1) = bounds(configs.iter().map(|c| err(c.suite)).chain([TARGET_MM]));
    let xlabel = if have_m4 {
        "Cortex-M4 instructions per simulated ms (flat maze)"
    } else {
        "host ns per simulated ms (flat maze; no target run)"
    };
    let mut ch = ChartBuilder::on(&left)
        .caption("Suite error vs cost on the target", ("sans-serif", 22))
        .margin(14)
        .x_label_area_size(44)
        .y_label_area_size(70)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
        .map_err(|e| e.to_string())?;
    ch.configure_mesh()
        .x_desc(xlabel)
        .y_desc("suite error (mm)")
        .label_style(("sans-serif", 13))
        .x_label_formatter(&|v| sig(*v))
        .y_label_formatter(&|v| sig(*v))
        .axis_desc_style(("sans-serif", 15))
        .draw()
        .map_err(|e| e.to_string())?;
    let dash = ShapeStyle {
        color: BLACK.mix(0.5),
        filled: false,
        stroke_width: 1,
    };
    ch.draw_series(DashedLineSeries::new(
        [(x0, TARGET_MM), (x1, TARGET_MM)],
        6,
        4,
        dash,
    ))
    .map_err(|e| e.to_string())?;
    if have_m4 {
        ch.draw_series(DashedLineSeries::new(
            [(BUDGET_PER_MS, y0), (BUDGET_PER_MS, y1)],
            6,
            4,
            dash,
        ))
        .map_err(|e| e.to_string())?;
    }
    ch.draw_series([Text::new(
        format!("target {TARGET_MM} mm"),
        (x0 * 1.1, TARGET_MM * 1.15),
        ("sans-serif", 13).into_font(),
    )])
    .map_err(|e| e.to_string())?;
    ch.draw_series([Text::new(
        format!("errors below {FLOOR:e} mm drawn at {FLOOR:e}"),
        (x0 * 1.1, y0 * 1.3),
        ("sans-serif", 12).into_font(),
    )])
    .map_err(|e| e.to_string())?;
    if have_m4 {
        ch.draw_series([Text::new(
            format!("budget {BUDGET_PER_MS}"),
            (BUDGET_PER_MS * 1.05, y1 / 1.6),
            ("sans-serif", 13).into_font(),
        )])
        .map_err(|e| e.to_string())?;
    }
    let mut front: Vec<(f64, f64)> = configs
        .iter()
        .filter(|c| c.pareto)
        .map(|c| (c.cost(), err(c.suite)))
        .collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    ch.draw_series(LineSeries::new(
        front.clone(),
        ShapeStyle {
            color: BLACK.mix(0.8),
            filled: false,
            stroke_width: 2,
        },
    ))
    .map_err(|e| e.to_string())?
    .label("Pareto front")
    .legend(|(x, y)| PathElement::new([(x, y), (x + 18, y)], BLACK.stroke_width(2)));
    for (b, name) in BACKENDS.iter().enumerate() {
        let pts: Vec<(f64, f64, u32, bool)> = configs
            .iter()
            .filter(|c| c.backend == b)
            .map(|c| (c.cost(), err(c.suite), c.k, c.pareto))
            .collect();
        let col = color(b);
        // Fixed steps: circles; event stepping: its own series of triangles.
        ch.draw_series(
            pts.iter()
                .filter(|p| !is_events(p.2))
                .map(|&(x, y, _, p)| Circle::new((x, y), if p { 6 } else { 4 }, col.filled())),
        )
        .map_err(|e| e.to_string())?
        .label(*name)
        .legend(move |(x, y)| Circle::new((x + 9, y), 5, col.filled()));
        ch.draw_series(
            pts.iter().filter(|p| is_events(p.2)).map(|&(x, y, _, p)| {
                TriangleMarker::new((x, y), if p { 9 } else { 7 }, col.filled())
            }),
        )
        .map_err(|e| e.to_string())?;
        ch.draw_series(pts.iter().map(|&(x, y, k, _)| {
            Text::new(
                label(k),
                (x * 1.06, y * 1.08),
                ("sans-serif", 11).into_font().color(&col),
            )
        }))
        .map_err(|e| e.to_string())?;
        // Ring around the firmware's default.
        if b == 0 {
            ch.draw_series(
                pts.iter()
                    .filter(|p| p.2 == firmware_k())
                    .map(|&(x, y, _, _)| Circle::new((x, y), 10, BLACK.stroke_width(1))),
            )
            .map_err(|e| e.to_string())?;
        }
    }
    // The legend entry of the event-stepping series (drawn per backend above).
    ch.draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
        .map_err(|e| e.to_string())?
        .label("event stepping (triangles)")
        .legend(|(x, y)| TriangleMarker::new((x + 9, y), 7, BLACK.filled()));
    ch.configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.4))
        .label_font(("sans-serif", 13))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(|e| e.to_string())?;

    // Right: host time per simulated ms (an event step is a whole frame), with
    // the peers (same suite error, maze time).
    let ms = |ns: f64, k: u32| ns * per_second(k) / 1000.0;
    let mut pts: Vec<(Engine, u32, f64, f64)> = configs
        .iter()
        .map(|c| {
            (
                Engine::Ours(c.backend),
                c.k,
                ms(c.host_ns, c.k),
                err(c.suite),
            )
        })
        .collect();
    for (peer, k) in PEERS
        .into_iter()
        .flat_map(|p| STEP_LOG2.into_iter().map(move |k| (p, k)))
    {
        let cell = |id: SceneId| study.cells.get(&(id, peer, k));
        if let (Some(i), Some(b), Some(c), Some(m)) = (
            cell(SceneId::Incline),
            cell(SceneId::Bounce),
            cell(SceneId::Corner),
            cell(SceneId::Maze),
        ) {
            let suite = i.err10.max(b.err_max).max(c.ana10.unwrap_or(0.0));
            pts.push((peer, k, ms(m.host.min_ns, k), err(suite)));
        }
    }
    let (x0, x1) = bounds(pts.iter().map(|p| p.2));
    let (y0, y1) = bounds(pts.iter().map(|p| p.3).chain([TARGET_MM]));
    let mut ch = ChartBuilder::on(&right)
        .caption(
            "Suite error vs host time, with rapier2d and Box2D v3",
            ("sans-serif", 22),
        )
        .margin(14)
        .x_label_area_size(44)
        .y_label_area_size(70)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
        .map_err(|e| e.to_string())?;
    ch.configure_mesh()
        .x_desc("host ns per simulated ms (flat maze)")
        .y_desc("suite error (mm)")
        .label_style(("sans-serif", 13))
        .x_label_formatter(&|v| sig(*v))
        .y_label_formatter(&|v| sig(*v))
        .axis_desc_style(("sans-serif", 15))
        .draw()
        .map_err(|e| e.to_string())?;
    ch.draw_series(DashedLineSeries::new(
        [(x0, TARGET_MM), (x1, TARGET_MM)],
        6,
        4,
        dash,
    ))
    .map_err(|e| e.to_string())?;
    for (b, name) in BACKENDS
        .iter()
        .enumerate()
        .map(|(b, n)| (Engine::Ours(b), *n))
        .chain([
            (Engine::Rapier, "rapier2d (f32)"),
            (Engine::Box2d, "Box2D v3 (f32)"),
        ])
    {
        let col = match b {
            Engine::Ours(i) => color(i),
            peer => peer_color(peer),
        };
        let mine: Vec<_> = pts.iter().filter(|p| p.0 == b).collect();
        ch.draw_series(
            mine.iter()
                .filter(|p| !is_events(p.1))
                .map(|p| Circle::new((p.2, p.3), 5, col.filled())),
        )
        .map_err(|e| e.to_string())?
        .label(name)
        .legend(move |(x, y)| Circle::new((x + 9, y), 5, col.filled()));
        ch.draw_series(
            mine.iter()
                .filter(|p| is_events(p.1))
                .map(|p| TriangleMarker::new((p.2, p.3), 7, col.filled())),
        )
        .map_err(|e| e.to_string())?;
        ch.draw_series(mine.iter().map(|p| {
            Text::new(
                label(p.1),
                (p.2 * 1.05, p.3 * 1.08),
                ("sans-serif", 11).into_font().color(&col),
            )
        }))
        .map_err(|e| e.to_string())?;
    }
    ch.draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
        .map_err(|e| e.to_string())?
        .label("event stepping (triangles)")
        .legend(|(x, y)| TriangleMarker::new((x + 9, y), 7, BLACK.filled()));
    ch.configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.4))
        .label_font(("sans-serif", 13))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(|e| e.to_string())?;
    root.present().map_err(|e| e.to_string())?;
    Ok(())
}
