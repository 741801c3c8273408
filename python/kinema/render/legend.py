"""The colour bar of `render_frames(legend=...)`: drawn once by Pillow, blended into each
frame."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .. import _core

#: A bar's end within this fraction of the larger end's magnitude is 0 up to rounding: a speed
#: of 7.31e-17 m/s beside 2 m/s is the rounding of a sum that is 0, not a value to print
#: (a double's rounding is 1.1e-16 of a value; sums of thousands of terms stay far below this).
ROUNDING = 1e-12


def bar_labels(vmin: float, vmax: float) -> tuple[str, str]:
    """The colour bar's two end labels, 3 significant digits each; an end within
    :data:`ROUNDING` of the other's magnitude prints as 0."""
    scale = max(abs(vmin), abs(vmax))

    def label(v: float) -> str:
        return "0" if abs(v) <= ROUNDING * scale else f"{v:.3g}"

    return label(vmin), label(vmax)


class _Legend:
    """A colour bar, drawn into frames: in the top right corner, on the time stamp's row (or
    under it where the row is too short for both), the quantity's name, `vmin`, a horizontal
    bar of the colormap (the colour of `vmin` on the left, its top colour on the right) and
    `vmax` (the map from `start` to 1, as the particles are coloured), on a panel of the
    background colour (3/4 opaque). Pillow draws it once, its text
    in DejaVu Sans (matplotlib's) as tall as the time stamp; each frame gets it by blending,
    `box` (x0, y0, x1, y1) pixels being where it goes."""

    def __init__(self, name, colormap, vmin, vmax, width, height, scale, ink, background, stamp_chars=0, start=0.0):
        from PIL import Image, ImageDraw

        scale = max(scale, 1)
        size = max(9, 7 * scale)  # the time stamp's glyphs are 7 font pixels of `scale` tall
        font = _legend_font(size)
        margin, pad, gap = 4 * scale, max(2, size // 5), max(3, size // 3)
        low, high = bar_labels(vmin, vmax)
        probe = ImageDraw.Draw(Image.new("L", (1, 1)))
        name_w, low_w, high_w = (round(probe.textlength(text, font=font)) for text in (name, low, high))
        bar_w, bar_h = int(min(max(0.2 * width, 40), 240)), max(6, round(0.75 * size))
        pw = pad + name_w + 2 * gap + low_w + gap + bar_w + gap + high_w + pad
        ph = size + size // 3 + 2 * pad
        x0 = width - margin - pw
        # On the stamp's row, centred on it, unless the two would meet; then under it.
        y0 = max(0, round(margin + 3.5 * scale - 0.5 * ph))
        if stamp_chars and x0 < margin + 6 * scale * stamp_chars + 2 * margin:
            y0 = margin + 7 * scale + margin
        self.box = (x0, y0, x0 + pw, y0 + ph)
        # out = frame·(1 − A) + C over the panel: A the opacity, C the colour times it.
        opacity = np.full((ph, pw, 1), 0.75, np.float32)
        colour = opacity * np.asarray(background, np.float32)
        mask = Image.new("L", (pw, ph), 0)
        draw = ImageDraw.Draw(mask)
        cy = ph // 2
        draw.text((pad, cy), name, fill=255, font=font, anchor="lm")
        bx0 = pad + name_w + 2 * gap + low_w + gap
        draw.text((bx0 - gap, cy), low, fill=255, font=font, anchor="rm")
        draw.text((bx0 + bar_w + gap, cy), high, fill=255, font=font, anchor="lm")
        m = np.asarray(mask, np.float32)[:, :, None] / 255.0
        colour = colour * (1.0 - m) + m * np.asarray(ink, np.float32)
        opacity = opacity * (1.0 - m) + m
        # The bar, opaque: left column the colour of vmin (the colormap at ``start``, where
        # render_frames puts the lowest value), right column its top colour.
        by0 = cy - bar_h // 2
        ramp = _core.colormap(np.linspace(float(start), 1.0, bar_w), colormap, 0.0, 1.0).astype(np.float32)
        colour[by0 : by0 + bar_h, bx0 : bx0 + bar_w] = ramp[None, :, :]
        opacity[by0 : by0 + bar_h, bx0 : bx0 + bar_w] = 1.0
        edge = np.asarray([128, 128, 128], np.float32)
        for rows, cols in (
            (slice(by0 - 1, by0), slice(bx0 - 1, bx0 + bar_w + 1)),
            (slice(by0 + bar_h, by0 + bar_h + 1), slice(bx0 - 1, bx0 + bar_w + 1)),
            (slice(by0, by0 + bar_h), slice(bx0 - 1, bx0)),
            (slice(by0, by0 + bar_h), slice(bx0 + bar_w, bx0 + bar_w + 1)),
        ):
            colour[rows, cols], opacity[rows, cols] = edge, 1.0
        self._opacity, self._colour = opacity, colour
        self.fits = x0 >= 0 and y0 + ph <= height

    def draw(self, frame: np.ndarray) -> None:
        x0, y0, x1, y1 = self.box
        region = frame[y0:y1, x0:x1]
        region[:] = np.clip(region * (1.0 - self._opacity) + self._colour + 0.5, 0, 255).astype(np.uint8)


def _legend_font(size: int):
    from PIL import ImageFont

    try:
        import matplotlib

        return ImageFont.truetype(str(Path(matplotlib.get_data_path()) / "fonts" / "ttf" / "DejaVuSans.ttf"), size)
    except (ImportError, OSError):
        try:
            return ImageFont.load_default(size=size)
        except TypeError:  # Pillow < 10.1: the fixed bitmap font
            return ImageFont.load_default()
