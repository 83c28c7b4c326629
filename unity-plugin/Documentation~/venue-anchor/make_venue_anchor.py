#!/usr/bin/env python3
"""Writes the venue anchor image and its printable pages (run from anywhere):

- venue-anchor.png (1024 x 1024, greyscale): a high-texture image for AR Foundation's
  ARTrackedImageManager and ARCore's Augmented Images - many corners at every scale, no
  repetition, no symmetry (a rotated copy never matches itself), full contrast;
- venue-anchor-A4.pdf and venue-anchor-A3.pdf: the image centred on the page at its
  physical width (180 mm on A4, 260 mm on A3), with the width printed under it so the app's
  reference image library can be given the size that was printed ("print at 100 %");
- a copy of the PNG as the Kotlin Recorder sample's asset
  (android/samples/recorder/src/main/assets/venue-anchor.png).

Deterministic: a fixed seed, so re-running writes the same pixels.
Needs numpy and Pillow (`pip install numpy pillow`).
"""

from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw, ImageFont

HERE = Path(__file__).resolve().parent
ANDROID_ASSET = HERE.parents[2] / "android/samples/recorder/src/main/assets/venue-anchor.png"
SIZE = 1024
SEED = 2023
DPI = 150  # the 1024-pixel image is printed at about 100–145 dpi anyway
# (page name, page width x height in mm, printed image width in mm)
PAGES = [("A4", (210, 297), 180), ("A3", (297, 420), 260)]


def anchor_image() -> Image.Image:
    rng = np.random.default_rng(SEED)
    img = Image.new("L", (SIZE, SIZE), 255)
    draw = ImageDraw.Draw(img)
    # Shapes from large to small: texture at every scale, corners everywhere.
    for size, count in [(260, 18), (120, 60), (50, 260), (18, 900)]:
        for _ in range(count):
            x, y = rng.integers(0, SIZE, 2)
            w, h = rng.integers(size // 3, size, 2)
            grey = int(rng.choice([0, 40, 90, 160, 215, 255]))
            shape = rng.integers(0, 3)
            box = [int(x), int(y), int(x + w), int(y + h)]
            if shape == 0:
                draw.rectangle(box, fill=grey)
            elif shape == 1:
                draw.ellipse(box, fill=grey)
            else:
                pts = [tuple(int(v) for v in rng.integers(-size // 2, size // 2, 2) + (x, y)) for _ in range(3)]
                draw.polygon(pts, fill=grey)
    # An asymmetric frame: thick black border, a white notch in the top-left corner only.
    draw.rectangle([0, 0, SIZE - 1, SIZE - 1], outline=0, width=24)
    draw.rectangle([24, 24, 120, 120], fill=255, outline=0, width=8)
    return img


def page(img: Image.Image, name: str, page_mm, width_mm) -> Image.Image:
    px = lambda mm: round(mm / 25.4 * DPI)
    sheet = Image.new("L", (px(page_mm[0]), px(page_mm[1])), 255)
    side = px(width_mm)
    top = px((page_mm[1] - width_mm) / 2) - px(10)
    left = (sheet.width - side) // 2
    sheet.paste(img.resize((side, side), Image.NEAREST), (left, top))
    draw = ImageDraw.Draw(sheet)
    text = (
        f"SiTAR venue anchor - {name}: image width {width_mm} mm "
        f"({width_mm / 1000:.3f} m). Print at 100 % (no scaling); "
        "enter this width in the reference image library."
    )
    try:
        font = ImageFont.load_default(size=px(3.5))
    except TypeError:  # Pillow < 10.1
        font = ImageFont.load_default()
    draw.text((left, top + side + px(6)), text, fill=0, font=font)
    return sheet


def main() -> None:
    img = anchor_image()
    img.save(HERE / "venue-anchor.png", optimize=True)
    ANDROID_ASSET.parent.mkdir(parents=True, exist_ok=True)
    img.save(ANDROID_ASSET, optimize=True)
    for name, page_mm, width_mm in PAGES:
        page(img, name, page_mm, width_mm).save(
            HERE / f"venue-anchor-{name}.pdf", resolution=DPI
        )
    print("wrote venue-anchor.png, venue-anchor-A4.pdf, venue-anchor-A3.pdf and", ANDROID_ASSET)


if __name__ == "__main__":
    main()
