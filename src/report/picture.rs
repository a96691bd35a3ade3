//! A picture drawn with `plotters`, written as SVG or PNG by the file's extension (`-`: SVG on
//! standard output), with the embedded font so no system font is needed.

use std::path::Path;
use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters_backend::{BackendColor, BackendCoord, BackendStyle, DrawingErrorKind};
use thiserror::Error;

/// DejaVu Sans cut to Latin-1 and the plots' symbols (assets/fonts/LICENSE-DejaVu.txt): the
/// bitmap backend draws text with it through `ab_glyph`, and both backends measure text with
/// it, so a plot looks the same on a machine without fonts (a container, CI).
static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans-subset.ttf");
/// The family name every plot asks for.
pub(crate) const FAMILY: &str = "sans-serif";

/// The file format of a picture, chosen by the file's extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    Svg,
    Png,
}

#[derive(Debug, Error)]
pub enum PictureError {
    #[error("{0}: the extension names no picture format (use .svg or .png, or - for SVG on standard output)")]
    UnknownFormat(String),
    #[error("{path}: {source}")]
    Write {
        path: String,
        source: std::io::Error,
    },
    #[error("drawing failed: {0}")]
    Draw(String),
    #[error("PNG encoding failed: {0}")]
    Png(#[from] png::EncodingError),
}

impl Format {
    /// `.svg` or `.png` (any case); `-` (standard output) is SVG.
    pub fn of(path: &Path) -> Result<Self, PictureError> {
        if crate::destination::is_stdout(path) {
            return Ok(Format::Svg);
        }
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("svg") => Ok(Format::Svg),
            Some("png") => Ok(Format::Png),
            _ => Err(PictureError::UnknownFormat(path.display().to_string())),
        }
    }
}

/// What a picture draws, on any `plotters` backend.
pub(crate) trait Picture {
    /// Size, px.
    fn size(&self) -> (u32, u32);
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static;
}

pub(crate) type DrawResult = Result<(), Box<dyn std::error::Error>>;

/// Register the embedded font under [`FAMILY`], once per process. `plotters` with `ab_glyph`
/// finds no font otherwise; the file is part of the binary, so this cannot fail in use (the
/// unit tests prove it parses).
pub fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let _ = plotters::style::register_font(FAMILY, FontStyle::Normal, FONT);
    });
}

/// The picture encoded in `format`.
pub(crate) fn encode(picture: &impl Picture, format: Format) -> Result<Vec<u8>, PictureError> {
    register_font();
    let size = picture.size();
    let draw_err = |e: Box<dyn std::error::Error>| PictureError::Draw(e.to_string());
    match format {
        Format::Svg => {
            let mut svg = String::new();
            {
                let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
                picture.draw(&root).map_err(draw_err)?;
                root.present()
                    .map_err(|e| PictureError::Draw(e.to_string()))?;
            }
            Ok(svg.into_bytes())
        }
        Format::Png => {
            let (w, h) = size;
            let mut rgb = vec![0u8; w as usize * h as usize * 3];
            {
                let root =
                    RowsLeftToRight(BitMapBackend::with_buffer(&mut rgb, size)).into_drawing_area();
                picture.draw(&root).map_err(draw_err)?;
                root.present()
                    .map_err(|e| PictureError::Draw(e.to_string()))?;
            }
            png_of(&rgb, size)
        }
    }
}

/// The bitmap backend with its horizontal lines drawn from left to right. plotters-bitmap
/// 0.3.7's `draw_line` fills a one-pixel-high line from `from` to `to + 1`, which leaves out
/// both ends of a line drawn right to left and all of one that is a pixel long: a tool path
/// traced leftwards at about a pixel a sample came out as a row of dots in a PNG (its SVG was
/// a clean line). Everything else is the bitmap backend's own.
struct RowsLeftToRight<'a>(BitMapBackend<'a>);

impl DrawingBackend for RowsLeftToRight<'_> {
    type ErrorType = <BitMapBackend<'static> as DrawingBackend>::ErrorType;

    fn get_size(&self) -> (u32, u32) {
        self.0.get_size()
    }

    fn ensure_prepared(&mut self) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.0.ensure_prepared()
    }

    fn present(&mut self) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.0.present()
    }

    fn draw_pixel(
        &mut self,
        point: BackendCoord,
        color: BackendColor,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.0.draw_pixel(point, color)
    }

    fn draw_line<S: BackendStyle>(
        &mut self,
        from: BackendCoord,
        to: BackendCoord,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        if from.1 == to.1 && to.0 < from.0 {
            self.0.draw_line(to, from, style)
        } else {
            self.0.draw_line(from, to, style)
        }
    }

    fn draw_rect<S: BackendStyle>(
        &mut self,
        upper_left: BackendCoord,
        bottom_right: BackendCoord,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.0.draw_rect(upper_left, bottom_right, style, fill)
    }

    fn blit_bitmap(
        &mut self,
        pos: BackendCoord,
        size: (u32, u32),
        src: &[u8],
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.0.blit_bitmap(pos, size, src)
    }
}

/// An 8-bit RGB buffer as a PNG file.
fn png_of(rgb: &[u8], (w, h): (u32, u32)) -> Result<Vec<u8>, PictureError> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header()?;
        writer.write_image_data(rgb)?;
        writer.finish()?;
    }
    Ok(out)
}

/// Draw `picture` into `path` in the format its extension names (`-`: SVG on standard output).
pub(crate) fn write(path: &Path, picture: &impl Picture) -> Result<(), PictureError> {
    let format = Format::of(path)?;
    let bytes = encode(picture, format)?;
    crate::destination::write(path, &bytes).map_err(|source| PictureError::Write {
        path: path.display().to_string(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_embedded_font_parses_and_has_the_plots_symbols() {
        use ab_glyph::Font;
        let f = ab_glyph::FontRef::try_from_slice(FONT).unwrap();
        for c in ['µ', '²', '³', '—', 'A', '0'] {
            assert_ne!(f.glyph_id(c).0, 0, "{c}");
        }
    }

    #[test]
    fn format_follows_the_extension() {
        assert_eq!(Format::of(Path::new("a/b.SVG")).unwrap(), Format::Svg);
        assert_eq!(Format::of(Path::new("b.png")).unwrap(), Format::Png);
        assert_eq!(Format::of(Path::new("-")).unwrap(), Format::Svg);
        for bad in ["x.jpg", "x", "svg"] {
            assert!(Format::of(Path::new(bad)).is_err(), "{bad}");
        }
    }
}
