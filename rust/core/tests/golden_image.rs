//! sitar-core's image properties against numpy + OpenCV
//! (`tests/golden/make_image_golden.py` wrote the images and `image_properties.csv`).
#![allow(missing_docs)]

use sitar_core::{FAST_THRESHOLD, ImageProperties, LumaImage, fast_corners};

fn golden(name: &str) -> String {
    format!("{}/tests/golden/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// Reads a binary PGM as written by the golden script (`P5\nW H\n255\n` + pixels).
fn read_pgm(name: &str) -> (Vec<u8>, usize, usize) {
    let bytes = std::fs::read(golden(&format!("images/{name}.pgm"))).unwrap();
    let mut parts = Vec::new();
    let mut start = 0;
    for (i, &b) in bytes.iter().enumerate() {
        if b == b'\n' || b == b' ' {
            parts.push(std::str::from_utf8(&bytes[start..i]).unwrap().to_owned());
            start = i + 1;
            if parts.len() == 4 {
                break;
            }
        }
    }
    assert_eq!(parts[0], "P5");
    let (w, h): (usize, usize) = (parts[1].parse().unwrap(), parts[2].parse().unwrap());
    (bytes[start..start + w * h].to_vec(), w, h)
}

/// The image with `pad` extra bytes (255) after every row.
fn padded(pixels: &[u8], w: usize, h: usize, pad: usize) -> Vec<u8> {
    let mut out = Vec::with_capacity(h * (w + pad));
    for row in pixels.chunks(w) {
        out.extend_from_slice(row);
        out.extend(std::iter::repeat_n(255u8, pad));
    }
    out
}

/// The image turned 90° clockwise: `(h, w)` in size.
fn turned(pixels: &[u8], w: usize, h: usize) -> Vec<u8> {
    let mut out = vec![0u8; w * h];
    for y in 0..h {
        for x in 0..w {
            out[x * h + (h - 1 - y)] = pixels[y * w + x];
        }
    }
    out
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * b.abs().max(1.0)
}

#[test]
fn properties_match_numpy_and_opencv() {
    let text = std::fs::read_to_string(golden("image_properties.csv")).unwrap();
    let mut names = Vec::new();
    for line in text.lines().skip(1) {
        let r: Vec<&str> = line.split(',').collect();
        let f = |i: usize| r[i].parse::<f64>().unwrap();
        let (pixels, w, h) = read_pgm(r[0]);
        assert_eq!((w, h), (r[1].parse().unwrap(), r[2].parse().unwrap()));
        let pad = 13;
        let data = padded(&pixels, w, h, pad);
        let image = LumaImage::new(&data, w as u32, h as u32, (w + pad) as u32).unwrap();
        let p = ImageProperties::measure(&image);
        let corners = fast_corners(&image, FAST_THRESHOLD);
        assert!(
            close(p.mean_brightness, f(3)),
            "{}: mean {} vs {}",
            r[0],
            p.mean_brightness,
            f(3)
        );
        assert!(
            close(p.contrast_std, f(4)),
            "{}: std {} vs {}",
            r[0],
            p.contrast_std,
            f(4)
        );
        assert!(
            close(p.laplacian_var, f(5)),
            "{}: laplacian {} vs {}",
            r[0],
            p.laplacian_var,
            f(5)
        );
        assert_eq!(corners as f64, f(6), "{}: FAST corners", r[0]);
        assert!(close(p.corners_per_10k, f(6) * 1e4 / (w * h) as f64));
        assert!(close(p.saturated_share, f(7)), "{}: saturated", r[0]);
        names.push(r[0].to_owned());
    }
    for needed in ["checkerboard", "flat_grey", "blurred", "dark"] {
        assert!(
            names.iter().any(|n| n == needed),
            "golden set lacks {needed}"
        );
    }
}

#[test]
fn properties_do_not_depend_on_the_sensor_orientation() {
    for name in ["shapes", "odd_size", "blurred"] {
        let (pixels, w, h) = read_pgm(name);
        let a = ImageProperties::measure(
            &LumaImage::new(&pixels, w as u32, h as u32, w as u32).unwrap(),
        );
        let t = turned(&pixels, w, h);
        let b =
            ImageProperties::measure(&LumaImage::new(&t, h as u32, w as u32, h as u32).unwrap());
        assert!(
            close(a.mean_brightness, b.mean_brightness) && close(a.laplacian_var, b.laplacian_var)
        );
        assert_eq!(a.corners_per_10k, b.corners_per_10k, "{name}");
    }
}

#[test]
fn the_golden_images_differ_as_their_names_say() {
    let measure = |name: &str| {
        let (pixels, w, h) = read_pgm(name);
        ImageProperties::measure(&LumaImage::new(&pixels, w as u32, h as u32, w as u32).unwrap())
    };
    let (sharp, blurred) = (measure("shapes"), measure("shapes_blurred"));
    assert!(blurred.laplacian_var < 0.05 * sharp.laplacian_var);
    assert!(measure("dark").mean_brightness < 40.0);
    assert!(measure("overexposed").saturated_share > 0.5);
    assert_eq!(measure("flat_grey").corners_per_10k, 0.0);
}
