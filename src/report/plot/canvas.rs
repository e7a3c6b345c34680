//! What every figure shares to be drawn and written: the DejaVu Sans font
//! shipped in the crate (so plots render on a machine without system fonts),
//! a titled drawing area with a legend strip below its plots, and a drawing
//! written as PNG (encoded in memory) and SVG, each file atomically.

use std::path::Path;
use std::sync::Once;

use plotters::prelude::*;

use crate::report::{DrawError, ReportError};

const FONT: &[u8] = include_bytes!("../fonts/DejaVuSans.ttf");

/// Registers the shipped font as `sans-serif`, once.
pub(super) fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The font is valid by construction; a failure would only lose text.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// Draws `$draw(area, args…)` — generic over the plotters backend — as a PNG
/// of `$size` pixels (drawn in memory) and as an SVG, each file written
/// atomically.
macro_rules! png_and_svg {
    ($draw:ident, $size:expr, $png:expr, $svg:expr $(, $arg:expr)*) => {{
        use ::plotters::prelude::{BitMapBackend, IntoDrawingArea, SVGBackend};
        use ::std::path::Path;
        use $crate::report::plot::canvas::{png_bytes, register_font};
        use $crate::report::{write_atomic, ReportError};
        register_font();
        let (png, svg, size): (&Path, &Path, (u32, u32)) = ($png, $svg, $size);
        let mut rgb = vec![0u8; 3 * size.0 as usize * size.1 as usize];
        $draw(BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area() $(, $arg)*)
            .map_err(|source| ReportError::Plot {
                path: png.to_path_buf(),
                source,
            })?;
        write_atomic(png, &png_bytes(&rgb, size, png)?)?;
        let mut text = String::new();
        $draw(SVGBackend::with_string(&mut text, size).into_drawing_area() $(, $arg)*)
            .map_err(|source| ReportError::Plot {
                path: svg.to_path_buf(),
                source,
            })?;
        write_atomic(svg, text.as_bytes())
    }};
}
pub(super) use png_and_svg;

/// A drawing area in pixels.
pub(super) type Area<DB> = DrawingArea<DB, plotters::coord::Shift>;

/// `root` titled, split into the plots above and a legend strip of
/// `legend_px` below them (legends there cover no data).
pub(super) fn titled_with_legend<DB: DrawingBackend>(
    root: &Area<DB>,
    title: &str,
    legend_px: i32,
) -> Result<(Area<DB>, Area<DB>), DrawError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let body = root.titled(title, ("sans-serif", 22))?;
    let height = body.dim_in_pixel().1 as i32;
    Ok(body.split_vertically(height - legend_px))
}

/// The PNG file of an RGB image of `size` pixels, in memory: the file is
/// written by [`write_atomic`](crate::report::write_atomic), whose errors
/// name the cause plainly (the bitmap backend's own writer reports
/// `ImageError(IoError(…))`).
pub(super) fn png_bytes(rgb: &[u8], size: (u32, u32), path: &Path) -> Result<Vec<u8>, ReportError> {
    use image::ImageEncoder;
    let mut bytes = Vec::new();
    image::codecs::png::PngEncoder::new(&mut bytes)
        .write_image(rgb, size.0, size.1, image::ColorType::Rgb8)
        .map_err(|e| ReportError::Plot {
            path: path.to_path_buf(),
            source: Box::new(e),
        })?;
    Ok(bytes)
}
