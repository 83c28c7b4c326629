//! A PDF drawing backend for plotters: each figure one page of vector paths, text in the
//! PDF's built-in Helvetica (no font file embedded), laid out with the figures' font metrics.
//! Hand-written because plotters has no PDF backend; it needs only lines, polygons, circles
//! and text, which PDF's content operators express directly.

use std::fmt::Write as _;

use plotters_backend::text_anchor::{HPos, VPos};
use plotters_backend::{
    BackendColor, BackendCoord, BackendStyle, BackendTextStyle, DrawingBackend, DrawingErrorKind,
    FontTransform,
};

/// The error type of the PDF backend (drawing into memory cannot fail).
#[derive(Debug)]
pub struct PdfError;

impl std::fmt::Display for PdfError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("PDF drawing error")
    }
}

impl std::error::Error for PdfError {}

/// One page being drawn: its size (points) and content stream.
pub struct PdfPage<'a> {
    size: (u32, u32),
    content: &'a mut String,
}

impl<'a> PdfPage<'a> {
    /// A page of `size` points drawing into `content`.
    pub fn new(content: &'a mut String, size: (u32, u32)) -> Self {
        Self { size, content }
    }

    fn y(&self, y: i32) -> f64 {
        f64::from(self.size.1) - f64::from(y)
    }

    /// Sets the colour; a translucent one is blended over the white page (PDF 1.4 without
    /// transparency groups: the figures draw translucent fills only over white).
    fn colour(&mut self, colour: BackendColor, stroke: bool) {
        let (r, g, b) = colour.rgb;
        let alpha = colour.alpha.clamp(0.0, 1.0);
        let blend = |c: u8| 1.0 - alpha * (1.0 - f64::from(c) / 255.0);
        let op = if stroke { "RG" } else { "rg" };
        let _ = writeln!(
            self.content,
            "{:.3} {:.3} {:.3} {op}",
            blend(r),
            blend(g),
            blend(b)
        );
    }

    fn path(&mut self, points: &[BackendCoord]) {
        for (k, &(x, y)) in points.iter().enumerate() {
            let op = if k == 0 { "m" } else { "l" };
            let _ = writeln!(self.content, "{x} {:.1} {op}", self.y(y));
        }
    }
}

/// Latin-1 text for Helvetica: a few math signs approximated, anything else `?`; PDF
/// string delimiters escaped.
fn pdf_text(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        let c = match c {
            '−' => '-',
            '₀' => '0',
            '₁' => '1',
            '₂' => '2',
            c if (c as u32) < 0x7f => c,
            _ => '?',
        };
        if matches!(c, '(' | ')' | '\\') {
            out.push('\\');
        }
        out.push(c);
    }
    out
}

impl DrawingBackend for PdfPage<'_> {
    type ErrorType = PdfError;

    fn get_size(&self) -> (u32, u32) {
        self.size
    }

    fn ensure_prepared(&mut self) -> Result<(), DrawingErrorKind<PdfError>> {
        Ok(())
    }

    fn present(&mut self) -> Result<(), DrawingErrorKind<PdfError>> {
        Ok(())
    }

    fn draw_pixel(
        &mut self,
        point: BackendCoord,
        colour: BackendColor,
    ) -> Result<(), DrawingErrorKind<PdfError>> {
        if colour.alpha > 0.0 {
            self.colour(colour, false);
            let _ = writeln!(
                self.content,
                "{} {:.1} 1 1 re f",
                point.0,
                self.y(point.1 + 1)
            );
        }
        Ok(())
    }

    fn draw_line<S: BackendStyle>(
        &mut self,
        from: BackendCoord,
        to: BackendCoord,
        style: &S,
    ) -> Result<(), DrawingErrorKind<PdfError>> {
        self.draw_path([from, to], style)
    }

    fn draw_rect<S: BackendStyle>(
        &mut self,
        upper_left: BackendCoord,
        bottom_right: BackendCoord,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<PdfError>> {
        if style.color().alpha == 0.0 {
            return Ok(());
        }
        self.colour(style.color(), !fill);
        let (x0, y0) = upper_left;
        let (w, h) = (bottom_right.0 - x0, bottom_right.1 - y0);
        let op = if fill { "f" } else { "S" };
        let _ = writeln!(
            self.content,
            "{} w {x0} {:.1} {w} {h} re {op}",
            style.stroke_width().max(1),
            self.y(bottom_right.1)
        );
        Ok(())
    }

    fn draw_path<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<PdfError>> {
        if style.color().alpha == 0.0 {
            return Ok(());
        }
        let points: Vec<BackendCoord> = path.into_iter().collect();
        if points.len() < 2 {
            return Ok(());
        }
        self.colour(style.color(), true);
        let _ = writeln!(self.content, "{} w 1 J 1 j", style.stroke_width().max(1));
        self.path(&points);
        self.content.push_str("S\n");
        Ok(())
    }

    fn draw_circle<S: BackendStyle>(
        &mut self,
        center: BackendCoord,
        radius: u32,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<PdfError>> {
        if style.color().alpha == 0.0 {
            return Ok(());
        }
        self.colour(style.color(), !fill);
        // Four Bézier quarter arcs (κ = 0.5523).
        let (cx, cy, r) = (f64::from(center.0), self.y(center.1), f64::from(radius));
        let k = 0.5523 * r;
        let _ = writeln!(
            self.content,
            "{} w {:.2} {cy:.2} m {:.2} {:.2} {:.2} {:.2} {cx:.2} {:.2} c {:.2} {:.2} {:.2} {:.2} {:.2} {cy:.2} c {:.2} {:.2} {:.2} {:.2} {cx:.2} {:.2} c {:.2} {:.2} {:.2} {:.2} {:.2} {cy:.2} c {}",
            style.stroke_width().max(1),
            cx + r,
            cx + r,
            cy + k,
            cx + k,
            cy + r,
            cy + r,
            cx - k,
            cy + r,
            cx - r,
            cy + k,
            cx - r,
            cx - r,
            cy - k,
            cx - k,
            cy - r,
            cy - r,
            cx + k,
            cy - r,
            cx + r,
            cy - k,
            cx + r,
            if fill { "f" } else { "S" }
        );
        Ok(())
    }

    fn fill_polygon<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        vert: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<PdfError>> {
        if style.color().alpha == 0.0 {
            return Ok(());
        }
        let points: Vec<BackendCoord> = vert.into_iter().collect();
        if points.len() < 3 {
            return Ok(());
        }
        self.colour(style.color(), false);
        self.path(&points);
        self.content.push_str("h f\n");
        Ok(())
    }

    fn draw_text<TStyle: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &TStyle,
        pos: BackendCoord,
    ) -> Result<(), DrawingErrorKind<PdfError>> {
        let (w, h) = self.estimate_text_size(text, style)?;
        let (w, h) = (f64::from(w), f64::from(h));
        let size = style.size();
        let anchor = style.anchor();
        // Offsets of the text's top-left from the anchor, in the text's own frame.
        let dx = match anchor.h_pos {
            HPos::Left => 0.0,
            HPos::Center => -w / 2.0,
            HPos::Right => -w,
        };
        let dy = match anchor.v_pos {
            VPos::Top => 0.0,
            VPos::Center => -h / 2.0,
            VPos::Bottom => -h,
        };
        // Baseline: about 80 % of the line height below the top.
        let (bx, by) = (dx, dy + 0.8 * h);
        let (a, b, c, d) = match style.transform() {
            FontTransform::None => (1.0, 0.0, 0.0, 1.0),
            FontTransform::Rotate90 => (0.0, -1.0, 1.0, 0.0),
            FontTransform::Rotate180 => (-1.0, 0.0, 0.0, -1.0),
            FontTransform::Rotate270 => (0.0, 1.0, -1.0, 0.0),
        };
        // Device point of the baseline start: rotate (bx, by) (y down) by the transform.
        let (px, py) = (f64::from(pos.0), f64::from(pos.1));
        let (ox, oy) = match style.transform() {
            FontTransform::None => (px + bx, py + by),
            FontTransform::Rotate90 => (px - by, py + bx),
            FontTransform::Rotate180 => (px - bx, py - by),
            FontTransform::Rotate270 => (px + by, py - bx),
        };
        self.colour(style.color(), false);
        let _ = writeln!(
            self.content,
            "BT /F1 {size:.1} Tf {a} {b} {c} {d} {ox:.2} {:.2} Tm ({}) Tj ET",
            self.y(oy.round() as i32),
            pdf_text(text)
        );
        Ok(())
    }
}

/// Builds a PDF file from pages of content streams.
pub fn document(pages: &[(String, (u32, u32))]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut offsets = Vec::new();
    out.extend_from_slice(b"%PDF-1.4\n%\xe2\xe3\xcf\xd3\n");
    let mut object = |out: &mut Vec<u8>, body: &[u8]| {
        offsets.push(out.len());
        out.extend_from_slice(format!("{} 0 obj\n", offsets.len()).as_bytes());
        out.extend_from_slice(body);
        out.extend_from_slice(b"\nendobj\n");
    };
    // 1: catalog, 2: pages, 3: font, then per page: page, content.
    let kids: Vec<String> = (0..pages.len())
        .map(|k| format!("{} 0 R", 4 + 2 * k))
        .collect();
    object(&mut out, b"<< /Type /Catalog /Pages 2 0 R >>");
    object(
        &mut out,
        format!(
            "<< /Type /Pages /Kids [{}] /Count {} >>",
            kids.join(" "),
            pages.len()
        )
        .as_bytes(),
    );
    object(
        &mut out,
        b"<< /Type /Font /Subtype /Type1 /BaseFont /Helvetica /Encoding /WinAnsiEncoding >>",
    );
    for (k, (content, (w, h))) in pages.iter().enumerate() {
        object(
            &mut out,
            format!(
                "<< /Type /Page /Parent 2 0 R /MediaBox [0 0 {w} {h}] /Resources << /Font << /F1 3 0 R >> >> /Contents {} 0 R >>",
                5 + 2 * k
            )
            .as_bytes(),
        );
        let mut stream = format!("<< /Length {} >>\nstream\n", content.len()).into_bytes();
        stream.extend_from_slice(content.as_bytes());
        stream.extend_from_slice(b"\nendstream");
        object(&mut out, &stream);
    }
    let xref = out.len();
    let mut table = format!("xref\n0 {}\n0000000000 65535 f \n", offsets.len() + 1);
    for offset in &offsets {
        let _ = writeln!(table, "{offset:010} 00000 n ");
    }
    let _ = write!(
        table,
        "trailer\n<< /Size {} /Root 1 0 R >>\nstartxref\n{xref}\n%%EOF\n",
        offsets.len() + 1
    );
    out.extend_from_slice(table.as_bytes());
    out
}
