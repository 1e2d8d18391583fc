//! The orientation a phone records beside its frames (issue 14 §1): the display
//! matrix that turns the stored frame into the frame a person sees.
//!
//! A phone held upright stores its sensor's landscape frames and tags the stream
//! with a display matrix (the `tkhd` matrix of MP4/MOV, which FFmpeg exports as
//! `AV_PKT_DATA_DISPLAYMATRIX` side data) that rotates them by 90°; a front camera
//! adds a mirror flip. [`Orientation`] is that matrix restricted to what phones
//! write, a rotation by a multiple of 90° after an optional left–right mirror, and
//! [`Orientation::displayed_from_stored`] maps pixels between the two frames, so
//! that every command measures the frame as displayed.
//!
//! The matrix's layout (libavutil `display.h`): nine 32-bit integers
//! `[a b u; c d v; x y w]`, `a b c d x y` in 16.16 fixed point, mapping a stored
//! point (p, q) (rows growing downward) to the displayed point
//! (a p + c q + x, b p + d q + y).

use std::fmt;

use serde::{Deserialize, Serialize};

/// The 16.16 fixed-point unit of the display matrix's `a b c d x y`.
const FIXED_ONE: f64 = 65536.0;

/// The 2.30 fixed-point unit of its `w`.
const W_ONE: i32 = 1 << 30;

/// How far (in units of 1) an entry of a right-angle matrix may stray from
/// −1, 0 or 1: a phone writes exact values; this absorbs the 16.16 rounding of a
/// matrix computed from cos and sin.
const RIGHT_ANGLE_TOLERANCE: f64 = 1e-3;

/// The stored frame's orientation relative to the displayed one: mirror left–right
/// (if `mirrored`), then rotate clockwise by `rotation_cw_deg`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Orientation {
    /// Clockwise rotation from the stored to the displayed frame \[deg\]: 0, 90,
    /// 180 or 270.
    pub rotation_cw_deg: u16,
    /// Whether the stored frame is mirrored left–right before the rotation.
    pub mirrored: bool,
}

impl fmt::Display for Orientation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.rotation_cw_deg, self.mirrored) {
            (0, false) => f.write_str("none (no display matrix, or the identity)"),
            (0, true) => f.write_str("mirrored left–right"),
            (r, false) => write!(f, "rotated {r}° clockwise"),
            (r, true) => write!(f, "mirrored left–right, then rotated {r}° clockwise"),
        }
    }
}

/// A pixel map between a stored frame of `stored` size and its displayed frame:
/// displayed (x, y) = R (p, q) + t with R a signed permutation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelMap {
    /// R as `[[a, c], [b, d]]`: x = a p + c q + tx, y = b p + d q + ty.
    r: [[i64; 2]; 2],
    t: [i64; 2],
    /// Stored frame (width, height) \[px\].
    pub stored: (usize, usize),
    /// Displayed frame (width, height) \[px\].
    pub displayed: (usize, usize),
}

impl Orientation {
    /// No rotation, no mirror.
    pub const IDENTITY: Orientation = Orientation {
        rotation_cw_deg: 0,
        mirrored: false,
    };

    /// A rotation of `rotation_cw_deg` clockwise after an optional mirror.
    ///
    /// # Errors
    /// A rotation that is not 0, 90, 180 or 270.
    pub fn new(rotation_cw_deg: u16, mirrored: bool) -> Result<Self, String> {
        if !matches!(rotation_cw_deg, 0 | 90 | 180 | 270) {
            return Err(format!(
                "a rotation of {rotation_cw_deg}°: only 0, 90, 180 and 270 (clockwise) are supported"
            ));
        }
        Ok(Self {
            rotation_cw_deg,
            mirrored,
        })
    }

    /// Whether the stored frame is the displayed frame.
    pub fn is_identity(&self) -> bool {
        *self == Self::IDENTITY
    }

    /// Whether width and height trade places (a quarter turn).
    pub fn swaps_axes(&self) -> bool {
        self.rotation_cw_deg % 180 == 90
    }

    /// `[[a, c], [b, d]]`, the linear part of stored → displayed (rows grow downward).
    fn linear(&self) -> [[i64; 2]; 2] {
        let (cos, sin) = match self.rotation_cw_deg {
            90 => (0, 1),
            180 => (-1, 0),
            270 => (0, -1),
            _ => (1, 0),
        };
        // A clockwise rotation on screen (y down) is [[cos, −sin], [sin, cos]];
        // the mirror diag(−1, 1) comes first.
        let m = if self.mirrored { -1 } else { 1 };
        [[m * cos, -sin], [m * sin, cos]]
    }

    /// The orientation a display matrix describes (the raw side data: nine
    /// native-endian `i32`).
    ///
    /// # Errors
    /// Data of the wrong length, or a matrix that is not a right-angle rotation
    /// with an optional mirror (a free angle, a scale or a shear), named with its
    /// entries.
    pub fn from_display_matrix(data: &[u8]) -> Result<Self, String> {
        if data.len() < 36 {
            return Err(format!(
                "a display matrix of {} bytes (expected 36)",
                data.len()
            ));
        }
        let m: Vec<i32> = data[..36]
            .chunks_exact(4)
            .map(|b| i32::from_ne_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        let [a, b, c, d] = [m[0], m[1], m[3], m[4]].map(|v| f64::from(v) / FIXED_ONE);
        let unit = |v: f64| -> Option<i64> {
            let r = v.round();
            ((v - r).abs() < RIGHT_ANGLE_TOLERANCE && r.abs() <= 1.0).then_some(r as i64)
        };
        let describe = || {
            format!(
                "display matrix [a b c d] = [{a:.4} {b:.4} {c:.4} {d:.4}]: only rotations by multiples of 90° and mirror flips are supported"
            )
        };
        let (Some(a), Some(b), Some(c), Some(d)) = (unit(a), unit(b), unit(c), unit(d)) else {
            return Err(describe());
        };
        let det = a * d - b * c;
        if det.abs() != 1 || a * c + b * d != 0 {
            return Err(describe());
        }
        // R = Rot(θ) · diag(±1, 1): its first column is (±cos θ, ±sin θ).
        let (cos, sin) = if det > 0 { (a, b) } else { (-a, -b) };
        let rotation_cw_deg = match (cos, sin) {
            (1, 0) => 0,
            (0, 1) => 90,
            (-1, 0) => 180,
            _ => 270,
        };
        Ok(Self {
            rotation_cw_deg,
            mirrored: det < 0,
        })
    }

    /// The display matrix that tags a stored frame of `stored` size with this
    /// orientation, as MP4's `tkhd` holds it (translation in continuous pixel
    /// coordinates, as phones write it).
    pub fn display_matrix(&self, stored: (usize, usize)) -> [i32; 9] {
        let [[a, c], [b, d]] = self.linear();
        let (w, h) = (stored.0 as i64, stored.1 as i64);
        let x = i64::from(a < 0) * w + i64::from(c < 0) * h;
        let y = i64::from(b < 0) * w + i64::from(d < 0) * h;
        let fixed = |v: i64| (v * FIXED_ONE as i64) as i32;
        [
            fixed(a),
            fixed(b),
            0,
            fixed(c),
            fixed(d),
            0,
            fixed(x),
            fixed(y),
            W_ONE,
        ]
    }

    /// The displayed frame's (width, height) of a stored frame of `stored` size.
    pub fn displayed_size(&self, stored: (usize, usize)) -> (usize, usize) {
        if self.swaps_axes() {
            (stored.1, stored.0)
        } else {
            stored
        }
    }

    /// The stored frame's (width, height) of a displayed frame of `displayed` size.
    pub fn stored_size(&self, displayed: (usize, usize)) -> (usize, usize) {
        // A quarter turn swaps the axes either way.
        self.displayed_size(displayed)
    }

    /// The pixel map of a stored frame of `stored` size.
    pub fn displayed_from_stored(&self, stored: (usize, usize)) -> PixelMap {
        let r = self.linear();
        let (w, h) = (stored.0 as i64 - 1, stored.1 as i64 - 1);
        // The offsets put the displayed corners at 0 and size − 1.
        let t = [
            i64::from(r[0][0] < 0) * w + i64::from(r[0][1] < 0) * h,
            i64::from(r[1][0] < 0) * w + i64::from(r[1][1] < 0) * h,
        ];
        PixelMap {
            r,
            t,
            stored,
            displayed: self.displayed_size(stored),
        }
    }
}

impl PixelMap {
    /// The displayed pixel (x, y) of the stored pixel (p, q).
    pub fn displayed(&self, p: usize, q: usize) -> (usize, usize) {
        let (p, q) = (p as i64, q as i64);
        let x = self.r[0][0] * p + self.r[0][1] * q + self.t[0];
        let y = self.r[1][0] * p + self.r[1][1] * q + self.t[1];
        (x as usize, y as usize)
    }

    /// The stored pixel (p, q) shown at the displayed pixel (x, y): R is
    /// orthogonal, so its inverse is its transpose.
    pub fn stored(&self, x: usize, y: usize) -> (usize, usize) {
        let (x, y) = (x as i64 - self.t[0], y as i64 - self.t[1]);
        let p = self.r[0][0] * x + self.r[1][0] * y;
        let q = self.r[0][1] * x + self.r[1][1] * y;
        (p as usize, q as usize)
    }

    /// The stored rectangle (columns, rows) that holds the displayed columns
    /// `columns` over every displayed row: an axis-aligned rectangle, since the
    /// map only permutes and flips the axes.
    pub fn stored_rect(
        &self,
        columns: std::ops::Range<usize>,
    ) -> (std::ops::Range<usize>, std::ops::Range<usize>) {
        let last_row = self.displayed.1 - 1;
        let corners = [
            self.stored(columns.start, 0),
            self.stored(columns.end - 1, last_row),
        ];
        let (p0, p1) = (
            corners[0].0.min(corners[1].0),
            corners[0].0.max(corners[1].0),
        );
        let (q0, q1) = (
            corners[0].1.min(corners[1].1),
            corners[0].1.max(corners[1].1),
        );
        (p0..p1 + 1, q0..q1 + 1)
    }

    /// Copy the displayed columns `columns` (all rows) of 3-byte pixels from the
    /// stored frame `stored` (rows `3 · stored width` apart) into `displayed`
    /// (rows `3 · displayed width` apart).
    pub fn copy_columns(
        &self,
        stored: &[u8],
        displayed: &mut [u8],
        columns: std::ops::Range<usize>,
    ) {
        let (sw, dw) = (3 * self.stored.0, 3 * self.displayed.0);
        for y in 0..self.displayed.1 {
            let row = &mut displayed[y * dw..(y + 1) * dw];
            for x in columns.clone() {
                let (p, q) = self.stored(x, y);
                let from = q * sw + 3 * p;
                row[3 * x..3 * x + 3].copy_from_slice(&stored[from..from + 3]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bytes(m: [i32; 9]) -> Vec<u8> {
        m.iter().flat_map(|v| v.to_ne_bytes()).collect()
    }

    #[test]
    fn an_iphone_portrait_matrix_is_a_quarter_turn_clockwise() {
        // What an iPhone held upright writes for 1920 × 1080 landscape frames:
        // [0 1 0; −1 0 0; 1080 0 1], which FFmpeg reports as "rotation of −90°"
        // (counter-clockwise −90°, so 90° clockwise).
        let one = 1 << 16;
        let m = [0, one, 0, -one, 0, 0, 1080 * one, 0, 1 << 30];
        let o = Orientation::from_display_matrix(&bytes(m)).unwrap();
        assert_eq!(o, Orientation::new(90, false).unwrap());
        assert_eq!(o.display_matrix((1920, 1080)), m);
        let map = o.displayed_from_stored((1920, 1080));
        assert_eq!(map.displayed, (1080, 1920));
        // The stored top-left corner shows at the top right; the top row becomes
        // the right-hand column.
        assert_eq!(map.displayed(0, 0), (1079, 0));
        assert_eq!(map.displayed(1919, 0), (1079, 1919));
        assert_eq!(map.displayed(0, 1079), (0, 0));
    }

    #[test]
    fn every_orientation_round_trips_through_its_matrix_and_its_map() {
        for rotation in [0, 90, 180, 270] {
            for mirrored in [false, true] {
                let o = Orientation::new(rotation, mirrored).unwrap();
                let back =
                    Orientation::from_display_matrix(&bytes(o.display_matrix((6, 4)))).unwrap();
                assert_eq!(back, o);
                let map = o.displayed_from_stored((6, 4));
                let mut seen = std::collections::HashSet::new();
                for q in 0..4 {
                    for p in 0..6 {
                        let (x, y) = map.displayed(p, q);
                        assert!(
                            x < map.displayed.0 && y < map.displayed.1,
                            "{o}: ({x}, {y})"
                        );
                        assert_eq!(map.stored(x, y), (p, q), "{o}");
                        seen.insert((x, y));
                    }
                }
                assert_eq!(seen.len(), 24, "{o}: a permutation of the pixels");
                // A mirror reverses the handedness: the stored corners (0,0) →
                // (1,0) → (0,1) turn the other way round on the display.
                let turn = |a: (usize, usize), b: (usize, usize), c: (usize, usize)| {
                    let (ax, ay) = (a.0 as i64, a.1 as i64);
                    (b.0 as i64 - ax) * (c.1 as i64 - ay) - (b.1 as i64 - ay) * (c.0 as i64 - ax)
                };
                let handed = turn(
                    map.displayed(0, 0),
                    map.displayed(1, 0),
                    map.displayed(0, 1),
                );
                assert_eq!(handed < 0, mirrored, "{o}");
            }
        }
    }

    #[test]
    fn a_band_of_displayed_columns_is_a_stored_rectangle() {
        let o = Orientation::new(90, false).unwrap();
        let map = o.displayed_from_stored((8, 6));
        // Displayed columns 2..4 of a 6 × 8 portrait frame: stored rows 2..4 from
        // the bottom (the stored rows 6 − 1 − x).
        let (p, q) = map.stored_rect(2..4);
        assert_eq!((p, q), (0..8, 2..4));
        let stored: Vec<u8> = (0..8 * 6).flat_map(|i| [i as u8; 3]).collect();
        let mut shown = vec![0u8; 3 * 8 * 6];
        map.copy_columns(&stored, &mut shown, 0..6);
        for y in 0..8 {
            for x in 0..6 {
                let (p, q) = map.stored(x, y);
                assert_eq!(shown[3 * (y * 6 + x)], (q * 8 + p) as u8);
            }
        }
    }

    #[test]
    fn free_angles_and_scales_are_refused_with_the_matrix() {
        let one = 1 << 16;
        let c = (f64::from(one) * 0.8) as i32;
        let s = (f64::from(one) * 0.6) as i32;
        let err = Orientation::from_display_matrix(&bytes([c, s, 0, -s, c, 0, 0, 0, 1 << 30]))
            .unwrap_err();
        assert!(err.contains("multiples of 90°"), "{err}");
        let err =
            Orientation::from_display_matrix(&bytes([2 * one, 0, 0, 0, one, 0, 0, 0, 1 << 30]))
                .unwrap_err();
        assert!(err.contains("2.0000"), "{err}");
        assert!(Orientation::from_display_matrix(&[0; 12]).is_err());
        assert!(Orientation::new(45, false).is_err());
    }
}
