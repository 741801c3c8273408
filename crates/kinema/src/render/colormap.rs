//! Colormaps: values → RGB8 through a lookup table, and categorical colours for ids.

use crate::Error;

/// A continuous colormap; values are normalised by `(v − vmin) / (vmax − vmin)`, clamped to
/// [0, 1] and looked up with linear interpolation between 33 evenly spaced anchors.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Colormap {
    /// Perceptually uniform blue → green → yellow (matplotlib's viridis, sampled).
    Viridis,
    /// Perceptually uniform black → purple → orange → cream (matplotlib's magma, sampled).
    Magma,
    /// Black → white.
    Gray,
}

/// The names accepted by [`Colormap::from_name`].
pub const COLORMAP_NAMES: &[&str] = &["viridis", "magma", "gray"];

impl Colormap {
    /// The colormap called `name` (see [`COLORMAP_NAMES`]).
    pub fn from_name(name: &str) -> Result<Self, Error> {
        match name {
            "viridis" => Ok(Colormap::Viridis),
            "magma" => Ok(Colormap::Magma),
            "gray" | "grey" => Ok(Colormap::Gray),
            _ => Err(Error::InvalidParameter {
                parameter: "colormap".into(),
                value: format!("'{name}'"),
                allowed: format!("one of {}", COLORMAP_NAMES.join(", ")),
            }),
        }
    }

    /// Colour of `t` in [0, 1] (clamped; NaN gives the bottom colour).
    pub fn at(self, t: f64) -> [u8; 3] {
        let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
        let lut: &[[u8; 3]; 33] = match self {
            Colormap::Viridis => &VIRIDIS,
            Colormap::Magma => &MAGMA,
            Colormap::Gray => {
                let g = (255.0 * t).round() as u8;
                return [g, g, g];
            }
        };
        let s = t * 32.0;
        let i = (s.floor() as usize).min(31);
        let f = s - i as f64;
        let (a, b) = (lut[i], lut[i + 1]);
        std::array::from_fn(|k| (a[k] as f64 + f * (b[k] as f64 - a[k] as f64)).round() as u8)
    }

    /// Colours of `values` normalised by `vmin`/`vmax` into `out` (3 bytes per value).
    /// `vmax == vmin` maps everything to the middle colour.
    pub fn map(self, values: &[f64], vmin: f64, vmax: f64, out: &mut [u8]) -> Result<(), Error> {
        if !(vmin.is_finite() && vmax.is_finite() && vmax >= vmin) {
            return Err(Error::InvalidParameter {
                parameter: "vmin/vmax".into(),
                value: format!("{vmin}/{vmax}"),
                allowed: "finite numbers with vmax >= vmin".into(),
            });
        }
        if out.len() != 3 * values.len() {
            return Err(Error::InvalidParameter {
                parameter: "colors".into(),
                value: format!("{} bytes", out.len()),
                allowed: format!("3 bytes per value ({})", 3 * values.len()),
            });
        }
        let span = vmax - vmin;
        for (v, o) in values.iter().zip(out.chunks_exact_mut(3)) {
            let t = if span > 0.0 { (v - vmin) / span } else { 0.5 };
            o.copy_from_slice(&self.at(t));
        }
        Ok(())
    }
}

/// Categorical colour of an id: the 10 colours of the tab10 palette, repeating every 10 ids.
pub fn categorical(id: u64) -> [u8; 3] {
    TAB10[(id % 10) as usize]
}

/// tab10 (matplotlib's default cycle), RGB8.
const TAB10: [[u8; 3]; 10] = [
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [214, 39, 40],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
    [127, 127, 127],
    [188, 189, 34],
    [23, 190, 207],
];

/// viridis at t = k/32, k = 0..=32, RGB8 (sampled from matplotlib's table).
const VIRIDIS: [[u8; 3]; 33] = [
    [68, 1, 84],
    [71, 13, 96],
    [72, 24, 106],
    [72, 35, 116],
    [71, 45, 123],
    [69, 55, 129],
    [66, 64, 134],
    [62, 73, 137],
    [59, 82, 139],
    [55, 91, 141],
    [51, 99, 141],
    [47, 107, 142],
    [44, 114, 142],
    [41, 122, 142],
    [38, 130, 142],
    [35, 137, 142],
    [33, 145, 140],
    [31, 152, 139],
    [31, 160, 136],
    [34, 167, 133],
    [40, 174, 128],
    [50, 182, 122],
    [63, 188, 115],
    [78, 195, 107],
    [94, 201, 98],
    [112, 207, 87],
    [132, 212, 75],
    [152, 216, 62],
    [173, 220, 48],
    [194, 223, 35],
    [216, 226, 25],
    [236, 229, 27],
    [253, 231, 37],
];

/// magma at t = k/32, k = 0..=32, RGB8 (sampled from matplotlib's table).
const MAGMA: [[u8; 3]; 33] = [
    [0, 0, 4],
    [3, 3, 18],
    [10, 8, 34],
    [19, 13, 52],
    [29, 17, 71],
    [41, 17, 90],
    [54, 16, 107],
    [68, 15, 118],
    [81, 18, 124],
    [93, 23, 127],
    [106, 28, 129],
    [118, 33, 129],
    [131, 38, 129],
    [144, 42, 129],
    [156, 46, 127],
    [170, 51, 125],
    [183, 55, 121],
    [196, 60, 117],
    [208, 65, 111],
    [220, 72, 105],
    [231, 82, 99],
    [239, 93, 94],
    [245, 107, 92],
    [249, 121, 93],
    [252, 137, 97],
    [253, 152, 105],
    [254, 167, 114],
    [254, 182, 124],
    [254, 196, 136],
    [254, 211, 149],
    [253, 226, 163],
    [252, 240, 178],
    [252, 253, 191],
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ends_and_clamping() {
        assert_eq!(Colormap::Viridis.at(0.0), VIRIDIS[0]);
        assert_eq!(Colormap::Viridis.at(1.0), VIRIDIS[32]);
        assert_eq!(Colormap::Viridis.at(7.0), VIRIDIS[32]);
        assert_eq!(Colormap::Viridis.at(-1.0), VIRIDIS[0]);
        assert_eq!(Colormap::Gray.at(0.5), [128, 128, 128]);
        assert!(Colormap::from_name("jet").is_err());
    }
}
