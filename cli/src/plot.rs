//! `force.svg`: the bottom force against time, simulated and (when the bundle has
//! them) measured, drawn with plotters' SVG backend.

use anyhow::anyhow;
use plotters::prelude::*;
use wagashi_io::ForceSeries;

/// Size of the drawing [px].
const SIZE: (u32, u32) = (900, 560);

/// Draws the series' legend at the upper right and writes the drawing out.
pub(crate) fn legend_and_present<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    root: &DrawingArea<DB, plotters::coord::Shift>,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .draw()?;
    root.present()
}

/// The SVG text of the force plot titled `title`.
pub fn force_svg(title: &str, simulated: &ForceSeries, measured: Option<&ForceSeries>) -> anyhow::Result<String> {
    let all = simulated.samples.iter().chain(measured.into_iter().flat_map(|m| &m.samples));
    let finite = all.filter(|s| s.t_s.is_finite() && s.force_n.is_finite());
    let (t_max, f_min, f_max) =
        finite.fold((0.0f64, 0.0f64, 0.0f64), |(t, lo, hi), s| (t.max(s.t_s), lo.min(s.force_n), hi.max(s.force_n)));
    let t_max = if t_max > 0.0 { t_max } else { 1.0 };
    let pad = 0.05 * (f_max - f_min).max(1e-9);
    let (y0, y1) = (if f_min < 0.0 { f_min - pad } else { 0.0 }, f_max + pad);

    let draw_err = |e: DrawingAreaErrorKind<std::io::Error>| anyhow!("drawing force.svg: {e}");
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 22))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(72)
            .build_cartesian_2d(0.0..t_max, y0..y1)
            .map_err(draw_err)?;
        chart
            .configure_mesh()
            .x_desc("time [s]")
            .y_desc("force on the bottom [N]")
            .bold_line_style(BLACK.mix(0.15))
            .light_line_style(BLACK.mix(0.05))
            .max_light_lines(2)
            .draw()
            .map_err(draw_err)?;
        if let Some(m) = measured {
            let points = m.samples.iter().map(|s| (s.t_s, s.force_n));
            chart
                .draw_series(LineSeries::new(points, RED.stroke_width(2)))
                .map_err(draw_err)?
                .label("measured")
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], RED.stroke_width(2)));
        }
        let points = simulated.samples.iter().map(|s| (s.t_s, s.force_n));
        chart
            .draw_series(LineSeries::new(points, BLUE.stroke_width(2)))
            .map_err(draw_err)?
            .label("simulated")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], BLUE.stroke_width(2)));
        legend_and_present(&mut chart, &root).map_err(draw_err)?;
    }
    Ok(svg)
}

/// Colours of the trials in the fit plots.
const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
];

/// `fit.svg`: per trial, the measured force (thin) and the force simulated with
/// the fitted (force or joint) set (thick), against time.
pub fn fit_svg(campaign: &calibrate::trial::Campaign, runs: &[fem_core::press::PressResult]) -> anyhow::Result<String> {
    let draw_err = |e: DrawingAreaErrorKind<std::io::Error>| anyhow!("drawing fit.svg: {e}");
    let mut t_max = 1e-9f64;
    let (mut f_min, mut f_max) = (0.0f64, 1e-12f64);
    for (trial, run) in campaign.trials.iter().zip(runs) {
        for (&(t, f), s) in trial.force.iter().zip(trial.simulated_force(run)) {
            if t.is_finite() && f.is_finite() && s.is_finite() {
                t_max = t_max.max(t);
                f_min = f_min.min(f).min(s);
                f_max = f_max.max(f).max(s);
            }
        }
    }
    let pad = 0.05 * (f_max - f_min);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        let mut chart = ChartBuilder::on(&root)
            .caption("measured (thin) and fitted (thick) force", ("sans-serif", 22))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(72)
            .build_cartesian_2d(0.0..t_max, (f_min - pad)..(f_max + pad))
            .map_err(draw_err)?;
        chart.configure_mesh().x_desc("time [s]").y_desc("force on the bottom [N]").draw().map_err(draw_err)?;
        for (i, (trial, run)) in campaign.trials.iter().zip(runs).enumerate() {
            let colour = PALETTE[i % PALETTE.len()];
            let measured = trial.force.iter().map(|&(t, f)| (t, f));
            chart.draw_series(LineSeries::new(measured, colour.mix(0.6).stroke_width(1))).map_err(draw_err)?;
            let simulated: Vec<(f64, f64)> = trial.force.iter().map(|p| p.0).zip(trial.simulated_force(run)).collect();
            chart
                .draw_series(LineSeries::new(simulated, colour.stroke_width(3)))
                .map_err(draw_err)?
                .label(trial.name.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], colour.stroke_width(3)));
        }
        legend_and_present(&mut chart, &root).map_err(draw_err)?;
    }
    Ok(svg)
}

/// `shapes.svg`: marker positions in the x-y plane: initial (grey), measured keep and
/// final (open circles), simulated with the shape (or joint) set (crosses), one
/// colour per phase.
pub fn shapes_svg(
    campaign: &calibrate::trial::Campaign,
    bundles: &[wagashi_io::Bundle],
    runs: &[fem_core::press::PressResult],
) -> anyhow::Result<String> {
    use calibrate::trial::Channel;
    let draw_err = |e: DrawingAreaErrorKind<std::io::Error>| anyhow!("drawing shapes.svg: {e}");
    let mut initial = Vec::new();
    // (phase, measured x-y, simulated x-y)
    type Point = (f64, f64);
    let mut points: Vec<(Channel, Point, Point)> = Vec::new();
    for ((trial, run), b) in campaign.trials.iter().zip(runs).zip(bundles) {
        for m in &b.markers {
            if let Some(p) = m.initial_position() {
                initial.push((p[0], p[1]));
            }
        }
        for p in trial.marker_pairs(run) {
            points.push((p.channel, (p.measured[0], p.measured[1]), (p.simulated[0], p.simulated[1])));
        }
    }
    let all = initial.iter().chain(points.iter().flat_map(|p| [&p.1, &p.2]));
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for &(x, y) in all.filter(|p| p.0.is_finite() && p.1.is_finite()) {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    if !x0.is_finite() {
        (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
    }
    let pad = 0.05 * (x1 - x0).max(y1 - y0).max(1e-6);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        let mut chart = ChartBuilder::on(&root)
            .caption("markers: measured (o) and simulated (x)", ("sans-serif", 22))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(72)
            .build_cartesian_2d((x0 - pad)..(x1 + pad), (y0 - pad)..(y1 + pad))
            .map_err(draw_err)?;
        chart.configure_mesh().x_desc("x [mm]").y_desc("y [mm]").draw().map_err(draw_err)?;
        let grey = RGBColor(150, 150, 150);
        chart
            .draw_series(initial.iter().map(|&p| Circle::new(p, 3, grey.filled())))
            .map_err(draw_err)?
            .label("initial")
            .legend(move |(x, y)| Circle::new((x + 12, y), 3, grey.filled()));
        for (channel, colour) in [(Channel::Keep, PALETTE[0]), (Channel::Final, PALETTE[1])] {
            let phase: Vec<_> = points.iter().filter(|p| p.0 == channel).collect();
            chart
                .draw_series(phase.iter().map(|p| Circle::new(p.1, 5, colour.stroke_width(2))))
                .map_err(draw_err)?
                .label(format!("{} measured", channel.as_str()))
                .legend(move |(x, y)| Circle::new((x + 12, y), 5, colour.stroke_width(2)));
            chart
                .draw_series(phase.iter().map(|p| Cross::new(p.2, 5, colour.stroke_width(2))))
                .map_err(draw_err)?
                .label(format!("{} simulated", channel.as_str()))
                .legend(move |(x, y)| Cross::new((x + 12, y), 5, colour.stroke_width(2)));
        }
        legend_and_present(&mut chart, &root).map_err(draw_err)?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;
    use wagashi_io::ForceSample;

    fn series(f: &[(f64, f64)]) -> ForceSeries {
        ForceSeries { samples: f.iter().map(|&(t_s, force_n)| ForceSample { t_s, force_n }).collect() }
    }

    #[test]
    fn the_plot_names_its_axes_and_series() {
        let sim = series(&[(0.0, 0.0), (1.0, 2.0), (2.0, 1.0)]);
        let meas = series(&[(0.0, 0.1), (1.0, 1.9)]);
        let svg = force_svg("mat1 & <friends>", &sim, Some(&meas)).unwrap();
        assert!(svg.starts_with("<svg"), "{}", &svg[..40]);
        for text in ["time [s]", "force on the bottom [N]", "simulated", "measured", "mat1 &amp; &lt;friends&gt;"] {
            assert!(svg.contains(text), "{text}");
        }
    }

    #[test]
    fn empty_and_non_finite_series_still_draw() {
        assert!(force_svg("x", &series(&[]), None).is_ok());
        assert!(force_svg("x", &series(&[(0.0, f64::NAN), (1.0, 1.0)]), None).is_ok());
    }
}
