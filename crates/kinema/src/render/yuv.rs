//! RGB8 → planar YUV 4:2:0 (BT.601, limited range), the input H.264 encoders take directly.
//!
//! Converting here, in parallel, spares the encoder its own single-threaded colour conversion
//! and halves the bytes sent to it (1.5 bytes per pixel instead of 3).

use rayon::prelude::*;

use super::camera::invalid;
use crate::Error;

/// Bytes of a `width × height` YUV 4:2:0 frame: a full-size Y plane, then U and V at half
/// resolution on both axes.
pub fn yuv420p_len(width: usize, height: usize) -> usize {
    width * height + 2 * (width / 2) * (height / 2)
}

/// Converts an RGB8 image (`width × height × 3` bytes, rows top first; both sides even) into
/// `out` ([`yuv420p_len`] bytes: planes Y, U, V).
///
/// BT.601 limited range in 8-bit fixed point (the coefficients × 256, rounded):
/// Y = 16 + (66 R + 129 G + 25 B + 128) / 256,
/// U = 128 + (−38 R − 74 G + 112 B + 128) / 256, V = 128 + (112 R − 94 G − 18 B + 128) / 256,
/// U and V from the mean of each 2 × 2 block of pixels.
pub fn rgb_to_yuv420p(rgb: &[u8], width: usize, height: usize, out: &mut [u8]) -> Result<(), Error> {
    if width == 0 || width % 2 != 0 {
        return Err(invalid("width", width, "an even number of pixels (4:2:0 halves it)"));
    }
    if height == 0 || height % 2 != 0 {
        return Err(invalid("height", height, "an even number of pixels (4:2:0 halves it)"));
    }
    if rgb.len() != width * height * 3 {
        return Err(invalid("rgb", format!("{} bytes", rgb.len()), "width × height × 3 bytes"));
    }
    if out.len() != yuv420p_len(width, height) {
        return Err(invalid("out", format!("{} bytes", out.len()), "width × height × 3 / 2 bytes"));
    }
    let (y_plane, uv) = out.split_at_mut(width * height);
    let (u_plane, v_plane) = uv.split_at_mut((width / 2) * (height / 2));
    let cw = width / 2;
    y_plane
        .par_chunks_mut(2 * width)
        .zip(u_plane.par_chunks_mut(cw))
        .zip(v_plane.par_chunks_mut(cw))
        .enumerate()
        .for_each(|(pair, ((y2, u), v))| {
            let src = &rgb[pair * 2 * width * 3..(pair + 1) * 2 * width * 3];
            let (top, bottom) = src.split_at(width * 3);
            for (y_row, row) in y2.chunks_exact_mut(width).zip([top, bottom]) {
                for (y, p) in y_row.iter_mut().zip(row.chunks_exact(3)) {
                    let (r, g, b) = (p[0] as i32, p[1] as i32, p[2] as i32);
                    *y = (16 + ((66 * r + 129 * g + 25 * b + 128) >> 8)) as u8;
                }
            }
            for i in 0..cw {
                let (a, b) = (&top[6 * i..6 * i + 6], &bottom[6 * i..6 * i + 6]);
                // Sums of the 2 × 2 block; dividing by 4 is folded into the final shift.
                let r = a[0] as i32 + a[3] as i32 + b[0] as i32 + b[3] as i32;
                let g = a[1] as i32 + a[4] as i32 + b[1] as i32 + b[4] as i32;
                let bl = a[2] as i32 + a[5] as i32 + b[2] as i32 + b[5] as i32;
                u[i] = (128 + ((-38 * r - 74 * g + 112 * bl + 512) >> 10)) as u8;
                v[i] = (128 + ((112 * r - 94 * g - 18 * bl + 512) >> 10)) as u8;
            }
        });
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn white_black_and_grey_map_to_the_limited_range() {
        for (c, y) in [(255u8, 235u8), (0, 16), (128, 126)] {
            let rgb = vec![c; 4 * 2 * 3];
            let mut out = vec![0; yuv420p_len(4, 2)];
            rgb_to_yuv420p(&rgb, 4, 2, &mut out).unwrap();
            assert!(out[..8].iter().all(|&v| v.abs_diff(y) <= 1), "{c}: {out:?}");
            assert!(out[8..].iter().all(|&v| v == 128), "{c}: {out:?}");
        }
        assert!(rgb_to_yuv420p(&[0; 9], 3, 1, &mut [0; 3]).is_err());
    }
}
