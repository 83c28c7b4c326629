//! Where figures go: SVG, PNG or PDF by the file's extension, one figure per file or, as
//! evo's `--save_plot` does, `FILE_raw.png` and `FILE_map.png` (one page each of a PDF).
//! Text uses the embedded DejaVu Sans (`assets/`), so PNG and PDF need no system fonts.

use std::path::{Path, PathBuf};
use std::sync::Once;

use anyhow::{Context, Result, bail};
use plotters::prelude::*;

use crate::figures::figure::{DrawResult, Drawing, ErrorFigure, PlotMode, SIZE};

/// DejaVu Sans (Bitstream Vera licence, `assets/DejaVuSans.LICENSE`): plotters' bitmap text
/// needs a font file, and a fresh machine may have none.
static FONT: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

/// Registers the embedded font as plotters' "sans-serif" (once; every plotters figure of
/// the binary needs it, since text is drawn with ab_glyph).
pub fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The embedded font is a valid TrueType file; a failure would only lose text.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// One page of a figure.
pub enum Page<'a> {
    /// Both panels of an error figure (SiTAR's `--plot FILE`).
    Both(&'a ErrorFigure, PlotMode),
    /// evo's "raw" figure: the error over the x dimension.
    Raw(&'a ErrorFigure),
    /// evo's "map" figure: the trajectories coloured by error.
    Map(&'a ErrorFigure, PlotMode),
    /// Any other figure, drawn by `crate::figures::panels`.
    Other(&'a Drawing),
}

impl Page<'_> {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, plotters::coord::Shift>,
    ) -> DrawResult<()>
    where
        DB::ErrorType: 'static,
    {
        match self {
            Page::Both(figure, mode) => crate::figures::plot::both(root, *mode, figure),
            Page::Raw(figure) => crate::figures::plot::raw(root, figure),
            Page::Map(figure, mode) => crate::figures::plot::map(root, *mode, figure),
            Page::Other(drawing) => crate::figures::panels::draw(root, drawing),
        }
    }
}

/// An image format, by extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Scalable vector graphics.
    Svg,
    /// A PNG bitmap.
    Png,
    /// PDF (vector).
    Pdf,
}

/// The format of `path` by its extension; anything else is an error naming the file.
pub fn format_of(path: &Path) -> Result<Format> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("svg") => Ok(Format::Svg),
        Some("png") => Ok(Format::Png),
        Some("pdf") => Ok(Format::Pdf),
        _ => bail!(
            "{}: the plot file's extension must be .png, .svg or .pdf",
            path.display()
        ),
    }
}

fn drawing_error(path: &Path, e: impl std::fmt::Display) -> anyhow::Error {
    anyhow::anyhow!("{}: cannot draw the plot: {e}", path.display())
}

/// The pages as bytes in `format` (several pages only for PDF).
pub fn render(
    path: &Path,
    format: Format,
    size: (u32, u32),
    pages: &[&Page<'_>],
) -> Result<Vec<u8>> {
    register_font();
    match format {
        Format::Svg => {
            let mut svg = String::new();
            {
                let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
                pages[0].draw(&root).map_err(|e| drawing_error(path, e))?;
                root.present().map_err(|e| drawing_error(path, e))?;
            }
            Ok(svg.into_bytes())
        }
        Format::Png => {
            let mut pixels = vec![255u8; size.0 as usize * size.1 as usize * 3];
            {
                let root = BitMapBackend::with_buffer(&mut pixels, size).into_drawing_area();
                pages[0].draw(&root).map_err(|e| drawing_error(path, e))?;
                root.present().map_err(|e| drawing_error(path, e))?;
            }
            let mut out = Vec::new();
            {
                let mut encoder = png::Encoder::new(&mut out, size.0, size.1);
                encoder.set_color(png::ColorType::Rgb);
                encoder.set_depth(png::BitDepth::Eight);
                let mut writer = encoder.write_header().map_err(|e| drawing_error(path, e))?;
                writer
                    .write_image_data(&pixels)
                    .map_err(|e| drawing_error(path, e))?;
            }
            Ok(out)
        }
        Format::Pdf => {
            let mut contents = Vec::new();
            for page in pages {
                let mut content = String::new();
                {
                    let root =
                        crate::figures::pdf::PdfPage::new(&mut content, size).into_drawing_area();
                    page.draw(&root).map_err(|e| drawing_error(path, e))?;
                    root.present().map_err(|e| drawing_error(path, e))?;
                }
                contents.push((content, size));
            }
            Ok(crate::figures::pdf::document(&contents))
        }
    }
}

/// Writes one page to exactly `path`.
pub fn save_one(path: &Path, size: (u32, u32), page: &Page<'_>) -> Result<()> {
    let bytes = render(path, format_of(path)?, size, &[page])?;
    std::fs::write(path, bytes)
        .with_context(|| format!("{}: cannot write the plot", path.display()))
}

/// evo's `PlotCollection.export`: a PDF gets every page; PNG and SVG get one file per
/// named page, `BASE_NAME.EXT`. Returns the files written.
pub fn save_collection(
    path: &Path,
    size: (u32, u32),
    pages: &[(&str, Page<'_>)],
) -> Result<Vec<PathBuf>> {
    let format = format_of(path)?;
    if format == Format::Pdf {
        let all: Vec<&Page<'_>> = pages.iter().map(|(_, p)| p).collect();
        let bytes = render(path, format, size, &all)?;
        std::fs::write(path, bytes)
            .with_context(|| format!("{}: cannot write the plot", path.display()))?;
        return Ok(vec![path.to_path_buf()]);
    }
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let extension = path
        .extension()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut written = Vec::new();
    for (name, page) in pages {
        let dest = path.with_file_name(format!("{stem}_{name}.{extension}"));
        let bytes = render(&dest, format, size, &[page])?;
        std::fs::write(&dest, bytes)
            .with_context(|| format!("{}: cannot write the plot", dest.display()))?;
        written.push(dest);
    }
    Ok(written)
}

/// evo's `-p`: shows the pages in the desktop's image viewer when there is a display;
/// otherwise says so and shows nothing. Returns whether something was shown.
pub fn show(
    size: (u32, u32),
    pages: &[(&str, Page<'_>)],
    console: &crate::io::console::Console,
) -> Result<bool> {
    let display = ["DISPLAY", "WAYLAND_DISPLAY"]
        .iter()
        .any(|v| std::env::var_os(v).is_some_and(|d| !d.is_empty()));
    if !display {
        console.warn(
            "no display ($DISPLAY and $WAYLAND_DISPLAY are not set): not showing the plot; use --save_plot FILE.png|svg|pdf to write it",
        );
        return Ok(false);
    }
    let dir = std::env::temp_dir().join(format!("sitar-plot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).with_context(|| format!("{}: cannot create", dir.display()))?;
    let files = save_collection(&dir.join("plot.png"), size, pages)?;
    for file in files {
        let opened = std::process::Command::new("xdg-open")
            .arg(&file)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn();
        if opened.is_err() {
            console.warn(&format!(
                "cannot start xdg-open to show the plot; it is in {}",
                file.display()
            ));
        }
    }
    Ok(true)
}

/// Draws `figure` (both panels) and writes it to `path`, SVG, PNG or PDF by the extension;
/// the error names the file.
pub fn write_error_figure(path: &Path, mode: PlotMode, figure: &ErrorFigure) -> Result<()> {
    save_one(path, SIZE, &Page::Both(figure, mode))
}
