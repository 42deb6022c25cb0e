//! `force.svg`: the bottom force against time, simulated and (when the bundle has
//! them) measured, drawn with plotters' SVG backend.

use anyhow::anyhow;
use plotters::prelude::*;
use wagashi_io::ForceSeries;

/// Size of the drawing [px].
const SIZE: (u32, u32) = (900, 560);

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
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .draw()
            .map_err(draw_err)?;
        root.present().map_err(draw_err)?;
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
