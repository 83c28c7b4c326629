//! The display-oriented thumbnail of a midpoint's camera image, as greyscale JPEG.

use crate::image::LumaImage;
use crate::{DisplayRotation, Error};

/// JPEG quality of thumbnails: 80 keeps edges readable at ~3–5 KB for 160×120.
pub const THUMBNAIL_QUALITY: u8 = 80;

/// A reused pixel buffer: working memory, not state, so any two compare equal.
#[derive(Debug, Clone, Default)]
pub(crate) struct PixelScratch(pub(crate) Vec<u8>);

impl PartialEq for PixelScratch {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// Size of a thumbnail whose longest side is `longest` (never larger than the image), in
/// sensor orientation: `(width, height)`, each ≥ 1.
pub fn thumbnail_size(width: u32, height: u32, longest: u32) -> (u32, u32) {
    let side = width.max(height);
    if side <= longest {
        return (width, height);
    }
    let scale = |v: u32| {
        ((u64::from(v) * u64::from(longest) + u64::from(side) / 2) / u64::from(side)).max(1) as u32
    };
    (scale(width), scale(height))
}

/// Box-filters `image` to `longest` px on its longest side and turns it clockwise by
/// `rotation` (to display orientation), into `out` (cleared first; its capacity is reused).
/// Returns the display size `(width, height)`.
pub fn downsample_rotated(
    image: &LumaImage<'_>,
    longest: u32,
    rotation: DisplayRotation,
    out: &mut Vec<u8>,
) -> (u32, u32) {
    let (sw, sh) = (image.width() as usize, image.height() as usize);
    let (tw, th) = thumbnail_size(sw as u32, sh as u32, longest);
    let (tw, th) = (tw as usize, th as usize);
    let (dw, dh) = match rotation {
        DisplayRotation::Deg0 | DisplayRotation::Deg180 => (tw, th),
        DisplayRotation::Deg90 | DisplayRotation::Deg270 => (th, tw),
    };
    out.clear();
    out.resize(dw * dh, 0);
    // Column sums of one band of source rows, per thumbnail column (on the stack up to
    // 1024 columns, the largest `thumbnail_px`).
    let mut sums = [0u32; 1024];
    let tw = tw.min(sums.len());
    let column_start: [usize; 1025] =
        std::array::from_fn(|tx| if tx <= tw { tx * sw / tw } else { sw });
    for ty in 0..th {
        let (y0, y1) = (ty * sh / th, ((ty + 1) * sh / th).max(ty * sh / th + 1));
        sums[..tw].fill(0);
        for y in y0..y1 {
            let row = image.row(y);
            for (tx, sum) in sums[..tw].iter_mut().enumerate() {
                let (x0, x1) = (
                    column_start[tx],
                    column_start[tx + 1].max(column_start[tx] + 1),
                );
                *sum += row[x0..x1].iter().map(|&p| u32::from(p)).sum::<u32>();
            }
        }
        for (tx, &sum) in sums[..tw].iter().enumerate() {
            let (x0, x1) = (
                column_start[tx],
                column_start[tx + 1].max(column_start[tx] + 1),
            );
            let n = ((y1 - y0) * (x1 - x0)) as u32;
            let value = ((sum + n / 2) / n) as u8;
            // Clockwise turn by θ: sensor (x, y) lands at display (dx, dy).
            let (dx, dy) = match rotation {
                DisplayRotation::Deg0 => (tx, ty),
                DisplayRotation::Deg90 => (th - 1 - ty, tx),
                DisplayRotation::Deg180 => (tw - 1 - tx, th - 1 - ty),
                DisplayRotation::Deg270 => (ty, tw - 1 - tx),
            };
            out[dy * dw + dx] = value;
        }
    }
    (dw as u32, dh as u32)
}

/// Encodes a greyscale `width`×`height` image as baseline JPEG ([`THUMBNAIL_QUALITY`]).
pub fn encode_jpeg(pixels: &[u8], width: u32, height: u32) -> Result<Vec<u8>, Error> {
    let (w, h) = (
        u16::try_from(width)
            .map_err(|_| Error::arg("thumbnail_px", format!("{width} is too wide for JPEG")))?,
        u16::try_from(height)
            .map_err(|_| Error::arg("thumbnail_px", format!("{height} is too tall for JPEG")))?,
    );
    let mut jpeg = Vec::with_capacity(pixels.len() / 4 + 1024);
    jpeg_encoder::Encoder::new(&mut jpeg, THUMBNAIL_QUALITY)
        .encode(pixels, w, h, jpeg_encoder::ColorType::Luma)
        .map_err(|e| Error::arg("thumbnail", format!("JPEG encoding failed: {e}")))?;
    Ok(jpeg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_keep_the_aspect_and_never_upscale() {
        assert_eq!(thumbnail_size(640, 480, 160), (160, 120));
        assert_eq!(thumbnail_size(480, 640, 160), (120, 160));
        assert_eq!(thumbnail_size(1920, 1080, 160), (160, 90));
        assert_eq!(thumbnail_size(100, 50, 160), (100, 50));
        assert_eq!(thumbnail_size(10_000, 1, 160), (160, 1));
    }

    /// A 4×2 image with distinct corners, turned each way, lands where a clockwise turn puts it.
    #[test]
    fn every_rotation_turns_clockwise() {
        // a b c d
        // e f g h
        let data = [1, 2, 3, 4, 5, 6, 7, 8];
        let img = LumaImage::new(&data, 4, 2, 4).unwrap();
        let mut out = Vec::new();
        let cases = [
            (DisplayRotation::Deg0, (4, 2), vec![1, 2, 3, 4, 5, 6, 7, 8]),
            // Turned clockwise: the left column (e over a) becomes the top row, e first.
            (DisplayRotation::Deg90, (2, 4), vec![5, 1, 6, 2, 7, 3, 8, 4]),
            (
                DisplayRotation::Deg180,
                (4, 2),
                vec![8, 7, 6, 5, 4, 3, 2, 1],
            ),
            (
                DisplayRotation::Deg270,
                (2, 4),
                vec![4, 8, 3, 7, 2, 6, 1, 5],
            ),
        ];
        for (rotation, size, expected) in cases {
            assert_eq!(downsample_rotated(&img, 160, rotation, &mut out), size);
            assert_eq!(out, expected, "{rotation:?}");
        }
    }

    #[test]
    fn box_filter_averages_blocks() {
        let data: Vec<u8> = (0..16).map(|i| if (i % 4) < 2 { 0 } else { 200 }).collect();
        let img = LumaImage::new(&data, 4, 4, 4).unwrap();
        let mut out = Vec::new();
        assert_eq!(
            downsample_rotated(&img, 2, DisplayRotation::Deg0, &mut out),
            (2, 2)
        );
        assert_eq!(out, vec![0, 200, 0, 200]);
    }

    #[test]
    fn jpeg_decodes_back_close_to_the_pixels() {
        let pixels: Vec<u8> = (0..160 * 120)
            .map(|i| (((i % 160) + (i / 160)) * 9 / 10) as u8)
            .collect();
        let jpeg = encode_jpeg(&pixels, 160, 120).unwrap();
        let mut decoder = jpeg_decoder::Decoder::new(&jpeg[..]);
        let back = decoder.decode().unwrap();
        let info = decoder.info().unwrap();
        assert_eq!((info.width, info.height), (160, 120));
        assert_eq!(info.pixel_format, jpeg_decoder::PixelFormat::L8);
        let max_diff = back
            .iter()
            .zip(&pixels)
            .map(|(a, b)| a.abs_diff(*b))
            .max()
            .unwrap();
        assert!(max_diff <= 8, "max difference {max_diff}");
    }
}
