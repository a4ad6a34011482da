//! Pictures of results: regression plots (the paper's Fig. 9), training curves and the stroke
//! models side by side.

use std::sync::Once;

use brush_model::{BrushProfile, Measurement};
use plotters::prelude::*;

use crate::{FigureError, Result};

static FONT: &[u8] = include_bytes!("../data/DejaVuSans-subset.ttf");

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The subset holds ASCII, °, ², α and β (DejaVu Sans, Bitstream Vera licence).
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

fn to_png(rgb: Vec<u8>, w: u32, h: u32) -> Result<Vec<u8>> {
    let img = image::RgbImage::from_raw(w, h, rgb).ok_or(FigureError::Size { width: w, height: h })?;
    let mut out = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png)?;
    Ok(out)
}

/// One output length of the regression plot: its label, how to read it from a measurement, and
/// the fitted terms.
type Output<'a> = (&'static str, fn(&Measurement) -> f64, &'a brush_model::Terms);

/// A closed polygon, mm.
type Ring = Vec<(f64, f64)>;

/// The regression plot: each of lt, lh, lr (rows) against h and against α (columns), the
/// measurements as points and the fitted model as a line (the other inputs held at their mean).
///
/// # Errors
/// When drawing or encoding fails.
pub fn regression_png(rows: &[Measurement], profile: &BrushProfile) -> Result<Vec<u8>> {
    register_font();
    let (w, h) = (1200u32, 900u32);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(FigureError::draw)?;
        let cells = root.split_evenly((3, 2));
        let n = rows.len().max(1) as f64;
        let mean_h = rows.iter().map(|m| m.press.h_mm).sum::<f64>() / n;
        let mean_a = rows.iter().map(|m| m.press.alpha_rad).sum::<f64>() / n;
        let mean_b = rows.iter().map(|m| m.press.beta_rad).sum::<f64>() / n;
        let outputs: [Output<'_>; 3] = [
            ("lt (mm)", |m| m.footprint.lt_mm, &profile.model.lt_mm),
            ("lh (mm)", |m| m.footprint.lh_mm, &profile.model.lh_mm),
            ("lr (mm)", |m| m.footprint.lr_mm, &profile.model.lr_mm),
        ];
        for (r, (label, get, terms)) in outputs.iter().enumerate() {
            for c in 0..2 {
                let area = &cells[r * 2 + c];
                let xs: Vec<f64> =
                    rows.iter().map(|m| if c == 0 { m.press.h_mm } else { m.press.alpha_rad.to_degrees() }).collect();
                let ys: Vec<f64> = rows.iter().map(get).collect();
                let (x0, x1) = (
                    xs.iter().cloned().fold(f64::INFINITY, f64::min),
                    xs.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
                );
                let (y0, y1) = (
                    ys.iter().cloned().fold(f64::INFINITY, f64::min),
                    ys.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
                );
                let (px, py) = (((x1 - x0) * 0.08).max(0.5), ((y1 - y0) * 0.1).max(0.1));
                let xlabel = if c == 0 { "h (mm)" } else { "α (°)" };
                let mut chart = ChartBuilder::on(area)
                    .caption(
                        format!("{} vs {}", label.split(' ').next().unwrap_or(label), if c == 0 { "h" } else { "α" }),
                        ("sans-serif", 20),
                    )
                    .margin(10)
                    .x_label_area_size(35)
                    .y_label_area_size(50)
                    .build_cartesian_2d((x0 - px)..(x1 + px), (y0 - py)..(y1 + py))
                    .map_err(FigureError::draw)?;
                chart
                    .configure_mesh()
                    .x_desc(xlabel)
                    .y_desc(*label)
                    .label_style(("sans-serif", 14))
                    .draw()
                    .map_err(FigureError::draw)?;
                chart
                    .draw_series(xs.iter().zip(&ys).map(|(&x, &y)| Circle::new((x, y), 3, BLUE.mix(0.6).filled())))
                    .map_err(FigureError::draw)?;
                let line: Vec<(f64, f64)> = (0..=40)
                    .map(|i| {
                        let x = x0 + (x1 - x0) * i as f64 / 40.0;
                        let y = if c == 0 {
                            terms.eval(x, mean_a, mean_b)
                        } else {
                            terms.eval(mean_h, x.to_radians(), mean_b)
                        };
                        (x, y)
                    })
                    .collect();
                chart.draw_series(LineSeries::new(line, RED.stroke_width(2))).map_err(FigureError::draw)?;
            }
        }
        root.present().map_err(FigureError::draw)?;
    }
    to_png(buf, w, h)
}

/// A training-curve plot: loss against step for each named series (log scale on the loss).
///
/// # Errors
/// When drawing or encoding fails.
pub fn loss_png(series: &[(&str, Vec<(f64, f64)>)]) -> Result<Vec<u8>> {
    register_font();
    let (w, h) = (900u32, 500u32);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(FigureError::draw)?;
        let all: Vec<(f64, f64)> = series.iter().flat_map(|s| s.1.iter().copied()).filter(|p| p.1 > 0.0).collect();
        let x1 = all.iter().map(|p| p.0).fold(1.0, f64::max);
        let y0 = all.iter().map(|p| p.1).fold(f64::INFINITY, f64::min).max(1e-8);
        let y1 = all.iter().map(|p| p.1).fold(0.0, f64::max).max(y0 * 10.0);
        let mut chart = ChartBuilder::on(&root)
            .caption("loss", ("sans-serif", 22))
            .margin(15)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..x1, (y0..y1).log_scale())
            .map_err(FigureError::draw)?;
        chart
            .configure_mesh()
            .x_desc("step")
            .y_desc("MSE")
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(FigureError::draw)?;
        for (i, (name, pts)) in series.iter().enumerate() {
            let colour = Palette99::pick(i).to_rgba();
            chart
                .draw_series(LineSeries::new(pts.iter().copied().filter(|p| p.1 > 0.0), colour.stroke_width(2)))
                .map_err(FigureError::draw)?
                .label(*name)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour));
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()
            .map_err(FigureError::draw)?;
        root.present().map_err(FigureError::draw)?;
    }
    to_png(buf, w, h)
}

/// Every stroke model's outline of one press side by side (the figure `maobi models --plot`
/// writes): one panel per model, named, with x and y axes in paper millimetres (y down, as on
/// the paper; the root end of the footprint at the origin) and a title naming the brush and the
/// press.
///
/// # Errors
/// When the press is outside the profile's calibrated range, or drawing or encoding fails.
pub fn models_png(profile: &BrushProfile, press: &brush_model::Press) -> Result<Vec<u8>> {
    use bezier_raster::ModelKind;
    register_font();
    let fp = profile.predict(press, brush_model::Extrapolation::Refuse)?;
    let anchor = brush_model::PointMm::new(0.0, 0.0);
    // Each model's outline as closed polygons, mm.
    let outlines: Vec<(&str, Vec<Ring>)> = ModelKind::ALL
        .iter()
        .map(|m| {
            let path = m.model().outline(&fp, anchor, press.beta_rad);
            let mut polys: Vec<Ring> = Vec::new();
            kurbo::flatten(&path, 0.01, |el| match el {
                kurbo::PathEl::MoveTo(p) => polys.push(vec![(p.x, p.y)]),
                kurbo::PathEl::LineTo(p) => {
                    if let Some(last) = polys.last_mut() {
                        last.push((p.x, p.y));
                    }
                }
                _ => {}
            });
            (m.name(), polys)
        })
        .collect();
    // One frame for all panels: the union of the outlines, with a margin.
    let pts = outlines.iter().flat_map(|(_, p)| p.iter().flatten());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for &(x, y) in pts {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    let pad = 0.08 * (x1 - x0).max(y1 - y0).max(1.0);
    let (x0, x1, y0, y1) = (x0 - pad, x1 + pad, y0 - pad, y1 + pad);
    // Equal scales on x and y (a circle looks round): the plot area of a panel is about
    // PANEL_W − 61 px wide; its height follows from the spans (at least 200 px, the y span
    // widened to match), plus about 110 px of title, caption and labels.
    const PANEL_W: u32 = 300;
    let plot_w = f64::from(PANEL_W - 61);
    let plot_h = (plot_w * (y1 - y0) / (x1 - x0)).max(200.0);
    let (yc, half) = (0.5 * (y0 + y1), 0.5 * (x1 - x0) * plot_h / plot_w);
    let (y0, y1) = (yc - half, yc + half);
    let (w, h) = (PANEL_W * outlines.len() as u32, plot_h.round() as u32 + 110);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(FigureError::draw)?;
        let root = root
            .titled(
                &format!(
                    "{}: h = {:.1} mm, α = {:.1}°, β = {:.1}° (lt {:.2}, lh {:.2}, lr {:.2} mm)",
                    profile.name,
                    press.h_mm,
                    press.alpha_rad.to_degrees(),
                    press.beta_rad.to_degrees(),
                    fp.lt_mm,
                    fp.lh_mm,
                    fp.lr_mm
                ),
                ("sans-serif", 20),
            )
            .map_err(FigureError::draw)?;
        let cells = root.split_evenly((1, outlines.len()));
        for (cell, (name, polys)) in cells.iter().zip(&outlines) {
            // y runs down the page, as on the paper.
            let mut chart = ChartBuilder::on(cell)
                .caption(*name, ("sans-serif", 18))
                .margin(8)
                .x_label_area_size(35)
                .y_label_area_size(45)
                .build_cartesian_2d(x0..x1, y1..y0)
                .map_err(FigureError::draw)?;
            chart
                .configure_mesh()
                .x_desc("x (mm)")
                .y_desc("y (mm)")
                .x_labels(5)
                .y_labels(5)
                .label_style(("sans-serif", 13))
                .draw()
                .map_err(FigureError::draw)?;
            chart
                .draw_series(polys.iter().map(|p| Polygon::new(p.clone(), BLACK.filled())))
                .map_err(FigureError::draw)?;
        }
        root.present().map_err(FigureError::draw)?;
    }
    to_png(buf, w, h)
}

/// A label's font size for a panel `width_px` wide, px (the labels stay legible on 64 px
/// panels and modest on 4096 px ones).
fn label_px(width_px: u32) -> u32 {
    (width_px / 16).clamp(9, 28)
}

/// Draws `lines` (text and colour) left-aligned from `(x, y)` downwards at `px` per line.
fn draw_lines(
    root: &DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>,
    lines: &[(&str, RGBColor)],
    x: i32,
    y: i32,
    px: u32,
) -> Result<()> {
    for (i, (text, colour)) in lines.iter().enumerate() {
        let style = ("sans-serif", px).into_font().color(colour);
        root.draw(&Text::new(*text, (x, y + i as i32 * (px as i32 + 2)), style)).map_err(FigureError::draw)?;
    }
    Ok(())
}

/// `side-by-side.png`: the panels left to right with a 4 px white gap, each with its label
/// above it (e.g. "reference (glyph)", "plan", "executed"), black ink on white.
///
/// # Errors
/// When drawing or encoding fails.
pub fn labelled_row_png(panels: &[(&str, &bezier_raster::Coverage)]) -> Result<Vec<u8>> {
    let rgb: Vec<(&str, image::RgbImage)> = panels
        .iter()
        .map(|(label, c)| {
            let gray = c.to_gray8();
            let rgb = gray.iter().flat_map(|&v| [v, v, v]).collect();
            let img = image::RgbImage::from_raw(c.width(), c.height(), rgb)
                .ok_or(FigureError::Size { width: c.width(), height: c.height() })?;
            Ok((*label, img))
        })
        .collect::<Result<_>>()?;
    let panels: Vec<(&str, &image::RgbImage)> = rgb.iter().map(|(l, img)| (*l, img)).collect();
    labelled_row_rgb_png(&panels)
}

/// [`labelled_row_png`] of colour panels (each label above its panel, 4 px white gaps).
///
/// # Errors
/// When drawing or encoding fails.
pub fn labelled_row_rgb_png(panels: &[(&str, &image::RgbImage)]) -> Result<Vec<u8>> {
    register_font();
    let gap = 4u32;
    let img_h = panels.iter().map(|(_, p)| p.height()).max().unwrap_or(0);
    let px = panels.iter().map(|(_, p)| label_px(p.width())).min().unwrap_or(9);
    let strip = px + 8;
    let w = panels.iter().map(|(_, p)| p.width()).sum::<u32>() + gap * panels.len().saturating_sub(1) as u32;
    let h = strip + img_h;
    let mut buf = vec![255u8; (w * h * 3) as usize];
    let mut x0 = 0u32;
    for (_, p) in panels {
        let row = (p.width() * 3) as usize;
        for (y, src) in p.as_raw().chunks_exact(row).enumerate() {
            let o = (((strip + y as u32) * w + x0) * 3) as usize;
            buf[o..o + row].copy_from_slice(src);
        }
        x0 += p.width() + gap;
    }
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let mut x0 = 0i32;
        for (label, p) in panels {
            draw_lines(&root, &[(label, BLACK)], x0 + 4, 3, px)?;
            x0 += (p.width() + gap) as i32;
        }
        root.present().map_err(FigureError::draw)?;
    }
    to_png(buf, w, h)
}

/// `overlay.png`: the glyph against a render (paper white, ink of both black, glyph ink the
/// render misses red, render ink outside the glyph blue), with a legend of the three colours
/// below the image.
///
/// # Errors
/// When the sizes differ, or drawing or encoding fails.
pub fn overlay_legend_png(reference: &bezier_raster::Coverage, render: &bezier_raster::Coverage) -> Result<Vec<u8>> {
    register_font();
    let plain = bezier_raster::overlay_png(reference, render)?;
    let img = image::load_from_memory(&plain)?.to_rgb8();
    let (w, img_h) = img.dimensions();
    let px = label_px(w);
    let lines = [
        ("black: glyph and plan", BLACK),
        ("red: glyph only (missed)", RGBColor(220, 0, 0)),
        ("blue: plan only (extra)", RGBColor(0, 0, 220)),
    ];
    let h = img_h + 6 + lines.len() as u32 * (px + 2);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    buf[..(w * img_h * 3) as usize].copy_from_slice(img.as_raw());
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        draw_lines(&root, &lines, 4, img_h as i32 + 4, px)?;
        root.present().map_err(FigureError::draw)?;
    }
    to_png(buf, w, h)
}

#[cfg(test)]
mod tests {
    use super::*;
    use bezier_raster::Coverage;

    fn bar(w: u32, h: u32) -> Coverage {
        let mut c = Coverage::new(w, h);
        for (i, v) in c.data_mut().iter_mut().enumerate() {
            *v = if (i as u32 % w) < w / 2 { 1.0 } else { 0.0 };
        }
        c
    }

    #[test]
    fn a_labelled_row_of_coverages_is_the_row_of_their_gray_pictures() {
        let (a, b) = (bar(64, 48), Coverage::new(32, 48));
        let png = labelled_row_png(&[("a", &a), ("b", &b)]).unwrap();
        let img = image::load_from_memory(&png).unwrap().to_rgb8();
        // 64 + 4 + 32 px wide; a strip for the labels above the 48 px panels.
        assert_eq!(img.width(), 100);
        let strip = img.height() - 48;
        assert_eq!(strip, label_px(32) + 8);
        // Ink is black, paper white, the gap white; the label strip has dark text on white.
        assert_eq!(img.get_pixel(0, strip).0, [0, 0, 0]);
        assert_eq!(img.get_pixel(63, strip).0, [255, 255, 255]);
        assert_eq!(img.get_pixel(65, strip + 10).0, [255, 255, 255]);
        assert!((0..100).any(|x| (0..strip).any(|y| img.get_pixel(x, y).0[0] < 128)));
        let gray = |c: &Coverage| {
            let rgb = c.to_gray8().iter().flat_map(|&v| [v, v, v]).collect();
            image::RgbImage::from_raw(c.width(), c.height(), rgb).unwrap()
        };
        assert_eq!(png, labelled_row_rgb_png(&[("a", &gray(&a)), ("b", &gray(&b))]).unwrap());
    }

    #[test]
    fn bad_inputs_are_named_errors() {
        let e = overlay_legend_png(&bar(32, 32), &bar(16, 32)).unwrap_err();
        assert!(matches!(e, FigureError::Raster(_)), "{e}");
        let pen1 = BrushProfile::builtin("pen1").unwrap();
        let deep = brush_model::Press { h_mm: 500.0, alpha_rad: 0.0, beta_rad: 0.0 };
        let e = models_png(&pen1, &deep).unwrap_err();
        assert!(matches!(e, FigureError::Profile(_)), "{e}");
    }

    #[test]
    fn the_plots_are_pngs_of_their_sizes() {
        let curve = vec![(0.0, 1.0), (1.0, 0.5), (2.0, 0.25)];
        let img = image::load_from_memory(&loss_png(&[("total", curve)]).unwrap()).unwrap();
        assert!(img.width() > 100 && img.height() > 100);
        let pen1 = BrushProfile::builtin("pen1").unwrap();
        let press = brush_model::Press { h_mm: 12.0, alpha_rad: 0.0, beta_rad: 0.0 };
        let img = image::load_from_memory(&models_png(&pen1, &press).unwrap()).unwrap();
        assert!(img.width() > 100 && img.height() > 100);
    }
}
