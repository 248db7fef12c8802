//! The performance-profile figure: ρ_s(τ) against τ on a log₂ axis, one step curve per solver,
//! drawn with plotters' SVG backend.

use super::profile::Profile;
use plotters::prelude::*;
use std::path::Path;

/// Line colours (one per inner solver; Tableau 10).
const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

/// Width in pixels of the legend column right of the axes.
const LEGEND_WIDTH: u32 = 240;

/// How one solver's curve is drawn.
#[derive(Debug, Clone, PartialEq)]
pub struct Curve {
    /// legend text
    pub label: String,
    /// index into the palette (taken modulo its length)
    pub color: usize,
    /// dashed instead of solid
    pub dashed: bool,
}

/// Why the figure could not be made.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// the number of curves differs from the number of solvers in the profile
    #[error("{curves} curve styles for {solvers} solvers")]
    Mismatch {
        /// curve styles given
        curves: usize,
        /// solvers in the profile
        solvers: usize,
    },
    /// plotters failed
    #[error("drawing the profile failed: {0}")]
    Draw(String),
    /// the file could not be written
    #[error("cannot write {path}: {source}")]
    Write {
        /// the SVG path
        path: std::path::PathBuf,
        /// the OS error
        source: std::io::Error,
    },
}

fn draw_err<E: std::fmt::Display>(e: E) -> PlotError {
    PlotError::Draw(e.to_string())
}

/// The right end of the τ axis: a little beyond the largest finite ratio, at least 2.
pub fn tau_end(profile: &Profile) -> f64 {
    (profile.largest_ratio() * 1.25).max(2.0)
}

/// Renders the profile as an SVG document (`width` × `height` pixels).
pub fn render_svg(
    profile: &Profile,
    curves: &[Curve],
    title: &str,
    (width, height): (u32, u32),
) -> Result<String, PlotError> {
    if curves.len() != profile.n_solvers() {
        return Err(PlotError::Mismatch {
            curves: curves.len(),
            solvers: profile.n_solvers(),
        });
    }
    let end = tau_end(profile);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        let root = root.titled(title, ("sans-serif", 20)).map_err(draw_err)?;
        // the legend goes in a column right of the axes, where it hides no curve
        let (plot_area, legend_area) = root.split_horizontally(width.saturating_sub(LEGEND_WIDTH));
        let mut chart = ChartBuilder::on(&plot_area)
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(55)
            .build_cartesian_2d((1.0..end).log_scale().base(2.0), 0.0..1.05)
            .map_err(draw_err)?;
        chart
            .configure_mesh()
            .x_desc("τ  (time / best time on the problem, log scale)")
            .y_desc("ρ(τ)  (fraction of problems solved)")
            .x_label_formatter(&|x| format!("{x:.0}"))
            .y_label_formatter(&|y| format!("{y:.1}"))
            .light_line_style(WHITE.mix(0.0))
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 15))
            .draw()
            .map_err(draw_err)?;
        for (s, curve) in curves.iter().enumerate() {
            let color = PALETTE[curve.color % PALETTE.len()];
            let style = ShapeStyle {
                color: color.to_rgba(),
                filled: false,
                stroke_width: 2,
            };
            let points = profile.steps(s, end);
            if curve.dashed {
                chart
                    .draw_series(DashedLineSeries::new(points, 8, 5, style))
                    .map_err(draw_err)?;
            } else {
                chart
                    .draw_series(LineSeries::new(points, style))
                    .map_err(draw_err)?;
            }
            // the legend swatch: two segments, touching (solid) or apart (dashed), then the label
            let (a, b) = if curve.dashed { (7, 12) } else { (10, 10) };
            let y = 40 + 24 * i32::try_from(s).unwrap_or(i32::MAX / 48);
            for x0 in [8, 8 + b] {
                legend_area
                    .draw(&PathElement::new(vec![(x0, y), (x0 + a, y)], style))
                    .map_err(draw_err)?;
            }
            legend_area
                .draw(&Text::new(
                    curve.label.clone(),
                    (8 + b + a + 8, y - 8),
                    ("sans-serif", 14),
                ))
                .map_err(draw_err)?;
        }
        root.present().map_err(draw_err)?;
    }
    Ok(svg)
}

/// Renders the profile and writes it to `path`.
pub fn write_svg(
    path: &Path,
    profile: &Profile,
    curves: &[Curve],
    title: &str,
) -> Result<(), PlotError> {
    let svg = render_svg(profile, curves, title, (900, 600))?;
    crate::outputs::write(path, svg.as_bytes()).map_err(|e| PlotError::Write {
        path: path.to_path_buf(),
        source: e.source,
    })
}

#[cfg(test)]
mod tests {
    use super::super::profile::performance_profile;
    use super::*;

    #[test]
    fn svg_has_one_curve_and_legend_entry_per_solver() {
        let p = performance_profile(&[
            vec![Some(1.0), Some(2.0)],
            vec![Some(3.0), Some(3.0)],
            vec![None, Some(0.5)],
        ])
        .unwrap();
        let curves = vec![
            Curve {
                label: "solver-A".into(),
                color: 0,
                dashed: false,
            },
            Curve {
                label: "solver-B".into(),
                color: 1,
                dashed: true,
            },
        ];
        let svg = render_svg(&p, &curves, "test", (600, 400)).unwrap();
        assert!(svg.trim_start().starts_with("<svg"));
        assert!(svg.contains("solver-A") && svg.contains("solver-B"));
        assert!(svg.contains("<polyline"));
        assert!(svg.contains("stroke=\"#1F77B4\"") || svg.contains("#1f77b4"));
        assert!(matches!(
            render_svg(&p, &curves[..1], "t", (600, 400)),
            Err(PlotError::Mismatch { .. })
        ));
    }
}
