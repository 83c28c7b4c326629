//! The camera's luminance plane and what can be measured on it: brightness, contrast,
//! sharpness, texture and saturation (the paper's future work: input-data properties).

use serde::{Deserialize, Serialize};

use crate::Error;

/// A borrowed 8-bit luminance plane (ARCore `Image` YUV_420_888 plane 0, AR Foundation
/// `XRCpuImage` Y plane) in sensor orientation, rows `stride` bytes apart.
#[derive(Debug, Clone, Copy)]
pub struct LumaImage<'a> {
    data: &'a [u8],
    width: usize,
    height: usize,
    stride: usize,
}

impl<'a> LumaImage<'a> {
    /// Wraps `data`. Width and height must be > 0, the stride at least the width, and `data`
    /// must cover `(height − 1) · stride + width` bytes (the last row may be unpadded, as in
    /// Android's `Image.Plane` buffers).
    pub fn new(
        data: &'a [u8],
        width: u32,
        height: u32,
        row_stride_bytes: u32,
    ) -> Result<Self, Error> {
        if width == 0 || height == 0 {
            return Err(Error::arg(
                "width/height",
                format!("{width}×{height} is empty"),
            ));
        }
        if row_stride_bytes < width {
            return Err(Error::arg(
                "row_stride_bytes",
                format!("{row_stride_bytes} is less than the width ({width})"),
            ));
        }
        let need = (u64::from(height) - 1) * u64::from(row_stride_bytes) + u64::from(width);
        if (data.len() as u64) < need {
            return Err(Error::arg(
                "luma",
                format!(
                    "{} bytes given, {need} needed for {width}×{height} with stride {row_stride_bytes}",
                    data.len()
                ),
            ));
        }
        Ok(Self {
            data,
            width: width as usize,
            height: height as usize,
            stride: row_stride_bytes as usize,
        })
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width as u32
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height as u32
    }

    /// Row `y` (exactly `width` bytes). `y` must be < height.
    #[inline(always)]
    pub(crate) fn row(&self, y: usize) -> &'a [u8] {
        &self.data[y * self.stride..y * self.stride + self.width]
    }
}

/// A pixel at or above this is counted as saturated: sensors clip a little below 255 after
/// the ISP's tone curve, and 250 keeps JPEG-style ringing of a clipped area counted.
pub const SATURATED_LUMA: u8 = 250;

/// FAST intensity threshold: a circle pixel differs from the centre by more than this. 20
/// (OpenCV's default is 10) keeps sensor noise on plain surfaces (σ ≈ 2–4) from making corners.
pub const FAST_THRESHOLD: u8 = 20;

/// What the camera saw at a midpoint, measured on its full luminance plane.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct ImageProperties {
    /// Mean luminance (0…255).
    pub mean_brightness: f64,
    /// Contrast: population standard deviation of the luminance.
    pub contrast_std: f64,
    /// Sharpness: variance of the 4-neighbour Laplacian (OpenCV `Laplacian`, ksize 1,
    /// reflect-101 border).
    pub laplacian_var: f64,
    /// Texture: FAST-9 corners ([`FAST_THRESHOLD`], non-maximum suppression, as OpenCV's
    /// `FastFeatureDetector`) per 10 000 pixels.
    pub corners_per_10k: f64,
    /// Share of pixels at or above [`SATURATED_LUMA`] (0…1).
    pub saturated_share: f64,
}

impl ImageProperties {
    /// Measures `image`. Allocation-free: one pass for the moments and the Laplacian, and FAST
    /// with a three-row ring of scores on the stack for images up to [`MAX_FAST_WIDTH`] wide
    /// (wider rows are measured on their first [`MAX_FAST_WIDTH`] columns).
    pub fn measure(image: &LumaImage<'_>) -> Self {
        let (w, h) = (image.width, image.height);
        let n = (w * h) as f64;
        let (mut sum, mut sum_sq, mut saturated) = (0u64, 0u64, 0u64);
        let (mut lap_sum, mut lap_sq) = (0i64, 0u64);
        debug_assert!(w < 1 << 24);
        for y in 0..h {
            let row = image.row(y);
            let up = image.row(reflect101(y as isize - 1, h));
            let down = image.row(reflect101(y as isize + 1, h));
            // Per row (the saturated count in u32: rows are < 2³² pixels), so the
            // loops vectorise; totals in 64 bits.
            let (mut row_sum, mut row_sq, mut row_sat) = (0u64, 0u64, 0u32);
            for &p in row {
                row_sum += u64::from(p);
                row_sq += u64::from(u32::from(p) * u32::from(p));
                row_sat += u32::from(p >= SATURATED_LUMA);
            }
            sum += row_sum;
            sum_sq += row_sq;
            saturated += u64::from(row_sat);
            let at = |x: usize, left: usize, right: usize| {
                i32::from(up[x]) + i32::from(down[x]) + i32::from(row[left]) + i32::from(row[right])
                    - 4 * i32::from(row[x])
            };
            let mut add = |l: i32| {
                lap_sum += i64::from(l);
                lap_sq += u64::from((l * l) as u32);
            };
            if w == 1 {
                add(at(0, 0, 0));
                continue;
            }
            add(at(0, 1, 1));
            add(at(w - 1, w - 2, w - 2));
            // Interior: windows of three over the row, zipped with the rows above and below.
            let (mut inner_sum, mut inner_sq) = (0i64, 0u64);
            for (((win, &u), &d), _) in row
                .windows(3)
                .zip(&up[1..w - 1])
                .zip(&down[1..w - 1])
                .zip(0..w - 2)
            {
                let l = i32::from(u) + i32::from(d) + i32::from(win[0]) + i32::from(win[2])
                    - 4 * i32::from(win[1]);
                inner_sum += i64::from(l);
                inner_sq += u64::from((l * l) as u32);
            }
            lap_sum += inner_sum;
            lap_sq += inner_sq;
        }
        let mean = sum as f64 / n;
        let var = (sum_sq as f64 / n - mean * mean).max(0.0);
        let lap_mean = lap_sum as f64 / n;
        let lap_var = (lap_sq as f64 / n - lap_mean * lap_mean).max(0.0);
        Self {
            mean_brightness: mean,
            contrast_std: var.sqrt(),
            laplacian_var: lap_var,
            corners_per_10k: fast_corners(image, FAST_THRESHOLD) as f64 * 10_000.0 / n,
            saturated_share: saturated as f64 / n,
        }
    }
}

/// OpenCV's `BORDER_REFLECT_101` index (`…2 1 | 0 1 2 … n−2 n−1 | n−2 …`), one step out.
#[inline(always)]
fn reflect101(i: isize, n: usize) -> usize {
    if n == 1 {
        0
    } else if i < 0 {
        (-i) as usize
    } else if i as usize >= n {
        2 * n - 2 - i as usize
    } else {
        i as usize
    }
}

/// Widest row FAST looks at (its working rows live on the stack: 4 × this many bytes).
pub const MAX_FAST_WIDTH: usize = 4096;

/// Bresenham circle of radius 3 (dx, dy), in order round the circle, as OpenCV's.
const CIRCLE: [(isize, isize); 16] = [
    (0, 3),
    (1, 3),
    (2, 2),
    (3, 1),
    (3, 0),
    (3, -1),
    (2, -2),
    (1, -3),
    (0, -3),
    (-1, -3),
    (-2, -2),
    (-3, -1),
    (-3, 0),
    (-3, 1),
    (-2, 2),
    (-1, 3),
];

/// Number of FAST-9 corners with non-maximum suppression over the 3×3 neighbourhood, as
/// OpenCV's `FAST(img, kp, threshold, true, TYPE_9_16)`: candidates at least 3 px from the
/// border, a corner when 9 contiguous circle pixels are all brighter than centre + t or all
/// darker than centre − t, kept when its score (the largest t for which it still is a corner)
/// beats all 8 neighbours' scores.
pub fn fast_corners(image: &LumaImage<'_>, threshold: u8) -> usize {
    let w = image.width.min(MAX_FAST_WIDTH);
    let h = image.height;
    if w < 7 || h < 7 {
        return 0;
    }
    let t = i32::from(threshold);
    // Scores of rows y−2, y−1, y (0 = no corner), as the OpenCV loop keeps them.
    let mut ring = [[0u8; MAX_FAST_WIDTH]; 3];
    let mut candidate = [0u8; MAX_FAST_WIDTH];
    let mut count = 0;
    for y in 3..h - 2 {
        let cur = (y - 3) % 3;
        ring[cur][..w].fill(0);
        if y < h - 3 {
            let rows: [&[u8]; 7] = std::array::from_fn(|i| image.row(y + i - 3));
            // Any 9-arc holds circle pixel 0 (3 below) or 8 (3 above): a vectorised pass marks
            // the pixels where either is out of the band, and only those are tested fully.
            for (((c, &below), &above), &v) in candidate[..w]
                .iter_mut()
                .zip(rows[6])
                .zip(rows[0])
                .zip(rows[3])
            {
                let (lo, hi) = (v.saturating_sub(threshold), v.saturating_add(threshold));
                *c = u8::from(below < lo || below > hi || above < lo || above > hi);
            }
            for x in 3..w - 3 {
                if candidate[x] == 0 {
                    continue;
                }
                let v = i32::from(rows[3][x]);
                let px = |k: usize| {
                    let (dx, dy) = CIRCLE[k];
                    i32::from(rows[(3 + dy) as usize][(x as isize + dx) as usize])
                };
                // 1 = darker than v − t, 2 = brighter than v + t.
                let class = |p: i32| -> u32 {
                    if p < v - t {
                        1
                    } else if p > v + t {
                        2
                    } else {
                        0
                    }
                };
                // Any 9-arc holds one of each opposite pair: a quick rejection first.
                let mut d = class(px(0)) | class(px(8));
                if d == 0 {
                    continue;
                }
                d &= class(px(2)) | class(px(10));
                d &= class(px(4)) | class(px(12));
                d &= class(px(6)) | class(px(14));
                if d == 0 {
                    continue;
                }
                let mut diffs = [0i32; 16];
                for (k, slot) in diffs.iter_mut().enumerate() {
                    *slot = v - px(k);
                }
                let score = arc_score(&diffs);
                if score > t {
                    // OpenCV stores `cornerScore` = the arc minimum − 1 (≥ t); as u8.
                    ring[cur][x] = (score - 1).clamp(1, 255) as u8;
                }
            }
        }
        // Non-maximum suppression of row y − 1 against rows y − 2 and y.
        if y >= 4 {
            let (prev, pprev) = ((y + 2) % 3, (y + 1) % 3); // rows y − 1, y − 2
            for x in 3..w - 3 {
                let s = ring[prev][x];
                if s == 0 {
                    continue;
                }
                let beats = |r: usize| s > ring[r][x - 1] && s > ring[r][x] && s > ring[r][x + 1];
                if s > ring[prev][x - 1] && s > ring[prev][x + 1] && beats(pprev) && beats(cur) {
                    count += 1;
                }
            }
        }
    }
    count
}

/// The largest `m` such that 9 contiguous circle differences `v − p` are all ≥ `m` or all
/// ≤ `−m` (0 if none is positive).
fn arc_score(d: &[i32; 16]) -> i32 {
    let mut best = 0;
    for start in 0..16 {
        let (mut lo, mut hi) = (i32::MAX, i32::MIN);
        for k in 0..9 {
            let v = d[(start + k) % 16];
            lo = lo.min(v);
            hi = hi.max(v);
        }
        best = best.max(lo).max(-hi);
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flat_image_has_no_contrast_no_corners() {
        let data = vec![128u8; 64 * 48];
        let p = ImageProperties::measure(&LumaImage::new(&data, 64, 48, 64).unwrap());
        assert_eq!(p.mean_brightness, 128.0);
        assert_eq!(p.contrast_std, 0.0);
        assert_eq!(p.laplacian_var, 0.0);
        assert_eq!(p.corners_per_10k, 0.0);
        assert_eq!(p.saturated_share, 0.0);
    }

    #[test]
    fn isolated_bright_dots_are_one_corner_each() {
        let (w, h) = (40usize, 40usize);
        let mut data = vec![20u8; w * h];
        for (x, y) in [(5, 5), (20, 10), (30, 30)] {
            data[y * w + x] = 220;
        }
        let img = LumaImage::new(&data, 40, 40, 40).unwrap();
        assert_eq!(fast_corners(&img, 20), 3);
        // A dot within 3 px of the border is no candidate (OpenCV's margin).
        data[2 * w + 20] = 220;
        let img = LumaImage::new(&data, 40, 40, 40).unwrap();
        assert_eq!(fast_corners(&img, 20), 3);
    }

    #[test]
    fn stride_padding_is_ignored() {
        let mut padded = vec![255u8; 10 * 16];
        for y in 0..10 {
            for x in 0..8 {
                padded[y * 16 + x] = (x * 10 + y) as u8;
            }
        }
        let tight: Vec<u8> = (0..10)
            .flat_map(|y| padded[y * 16..y * 16 + 8].to_vec())
            .collect();
        let a = ImageProperties::measure(&LumaImage::new(&padded, 8, 10, 16).unwrap());
        let b = ImageProperties::measure(&LumaImage::new(&tight, 8, 10, 8).unwrap());
        assert_eq!(a, b);
    }

    #[test]
    fn bad_planes_are_refused_naming_the_problem() {
        let data = [0u8; 100];
        let msg = |r: Result<LumaImage<'_>, Error>| r.unwrap_err().to_string();
        assert!(msg(LumaImage::new(&data, 0, 10, 10)).contains("empty"));
        assert!(msg(LumaImage::new(&data, 10, 10, 9)).contains("row_stride_bytes"));
        assert!(msg(LumaImage::new(&data, 10, 11, 10)).contains("110 needed"));
        // The last row may be unpadded.
        assert!(LumaImage::new(&data, 10, 10, 10).is_ok());
        assert!(LumaImage::new(&data[..91], 1, 10, 10).is_ok());
    }
}
