//! A 5×7 bitmap font for time stamps: digits, `.`, `-`, `+`, `:`, `=`, space and the letters
//! `t`, `s`, `e` (enough for "t = 1.250 s" and "t = 2.5e-3 s").

use crate::Error;

/// Glyph width in font pixels (plus one column of spacing between glyphs).
pub const GLYPH_W: usize = 5;
/// Glyph height in font pixels.
pub const GLYPH_H: usize = 7;

/// Rows of a glyph, top first; bit 4 is the leftmost column.
fn glyph(c: char) -> Option<[u8; 7]> {
    Some(match c {
        '0' => [0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E],
        '1' => [0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E],
        '2' => [0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F],
        '3' => [0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E],
        '4' => [0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02],
        '5' => [0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E],
        '6' => [0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E],
        '7' => [0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08],
        '8' => [0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E],
        '9' => [0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C],
        '.' => [0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C],
        '-' => [0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00],
        '+' => [0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00],
        ':' => [0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00],
        '=' => [0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00],
        ' ' => [0x00; 7],
        't' => [0x08, 0x08, 0x1C, 0x08, 0x08, 0x09, 0x06],
        's' => [0x00, 0x00, 0x0E, 0x10, 0x0E, 0x01, 0x1E],
        'e' => [0x00, 0x00, 0x0E, 0x11, 0x1F, 0x10, 0x0E],
        _ => return None,
    })
}

/// Characters [`draw_text`] can draw.
pub const FONT_CHARS: &str = "0123456789.-+:= tse";

/// Draws `text` into an RGB8 image (`width × height × 3` bytes, rows top first) with its
/// top-left corner at pixel `at` = (column, row), each font pixel a `scale × scale` block of `color`.
/// Parts outside the image are clipped. Returns the drawn width in pixels.
pub fn draw_text(
    image: &mut [u8],
    width: usize,
    height: usize,
    at: [usize; 2],
    scale: usize,
    color: [u8; 3],
    text: &str,
) -> Result<usize, Error> {
    if image.len() != width * height * 3 {
        return Err(super::camera::invalid(
            "image",
            format!("{} bytes", image.len()),
            "width × height × 3 bytes",
        ));
    }
    if scale == 0 {
        return Err(super::camera::invalid("scale", scale, "an integer >= 1"));
    }
    let glyphs = text
        .chars()
        .map(|c| {
            glyph(c).ok_or_else(|| {
                super::camera::invalid("text", format!("{c:?} in {text:?}"), &format!("characters of {FONT_CHARS:?}"))
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let [x, y] = at;
    let advance = (GLYPH_W + 1) * scale;
    for (k, rows) in glyphs.iter().enumerate() {
        let gx = x + k * advance;
        for (r, bits) in rows.iter().enumerate() {
            for c in 0..GLYPH_W {
                if bits & (0x10 >> c) == 0 {
                    continue;
                }
                for py in (y + r * scale)..(y + (r + 1) * scale).min(height) {
                    for px in (gx + c * scale)..(gx + (c + 1) * scale).min(width) {
                        let o = 3 * (py * width + px);
                        image[o..o + 3].copy_from_slice(&color);
                    }
                }
            }
        }
    }
    Ok(glyphs.len() * advance)
}
