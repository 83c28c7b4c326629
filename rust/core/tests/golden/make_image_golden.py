#!/usr/bin/env python3
"""Independent reference values for sitar-core's image properties (numpy + OpenCV).

Writes, next to this script:
  images/<name>.pgm        fixed 8-bit test images (binary PGM)
  image_properties.csv     name,width,height,mean_brightness,contrast_std,laplacian_var,
                           fast_corners,saturated_share

  mean/std      numpy (population std)
  laplacian_var cv2.Laplacian(img, CV_64F) (ksize 1: 4-neighbour, BORDER_REFLECT_101), .var()
  fast_corners  cv2.FastFeatureDetector (threshold 20, non-maximum suppression, TYPE_9_16)
  saturated     share of pixels >= 250

Run: python3 make_image_golden.py   (numpy, opencv-python-headless; deterministic seed)
"""
import csv
import os

import cv2
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
rng = np.random.default_rng(20231016)
W, H = 160, 120


def checkerboard(square=10):
    y, x = np.mgrid[0:H, 0:W]
    return np.where(((x // square) + (y // square)) % 2 == 0, 40, 210).astype(np.uint8)


def shapes():
    img = np.full((H, W), 110, np.uint8)
    for _ in range(25):
        x0, y0 = rng.integers(0, W - 10), rng.integers(0, H - 10)
        w, h = rng.integers(4, 30), rng.integers(4, 30)
        img[y0:y0 + h, x0:x0 + w] = rng.integers(0, 256)
    noise = rng.normal(0, 3, size=img.shape)
    return np.clip(img + noise, 0, 255).astype(np.uint8)


def images():
    board = checkerboard()
    scene = shapes()
    return {
        "checkerboard": board,
        "flat_grey": np.full((H, W), 128, np.uint8),
        "blurred": cv2.GaussianBlur(board, (7, 7), 2.0),
        "dark": (board // 6).astype(np.uint8),
        "shapes": scene,
        "shapes_blurred": cv2.GaussianBlur(scene, (9, 9), 3.0),
        "overexposed": np.clip(scene.astype(np.int32) * 3, 0, 255).astype(np.uint8),
        "odd_size": scene[3:80, 5:128].copy(),
    }


def properties(img):
    lap = cv2.Laplacian(img, cv2.CV_64F)
    fast = cv2.FastFeatureDetector_create(
        threshold=20, nonmaxSuppression=True, type=cv2.FAST_FEATURE_DETECTOR_TYPE_9_16
    )
    corners = len(fast.detect(img, None))
    return [
        float(img.mean()),
        float(img.std()),
        float(lap.var()),
        corners,
        float((img >= 250).mean()),
    ]


def main():
    os.makedirs(os.path.join(HERE, "images"), exist_ok=True)
    rows = []
    for name, img in images().items():
        h, w = img.shape
        with open(os.path.join(HERE, "images", f"{name}.pgm"), "wb") as f:
            f.write(f"P5\n{w} {h}\n255\n".encode())
            f.write(img.tobytes())
        rows.append([name, w, h] + [repr(v) for v in properties(img)])
    with open(os.path.join(HERE, "image_properties.csv"), "w", newline="") as f:
        out = csv.writer(f, lineterminator="\n")
        out.writerow(["name", "width", "height", "mean_brightness", "contrast_std",
                      "laplacian_var", "fast_corners", "saturated_share"])
        out.writerows(rows)


if __name__ == "__main__":
    main()
