//! Connected components of a binary mask (8-connected, as MATLAB's BWCONNCOMP
//! in 2-D), with the moments needed for a bounding box and a PCA.

/// One connected component of a mask, with its raw moments about the origin of
/// pixel centres (column + ½, row + ½).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Component {
    pub pixels: usize,
    /// Inclusive bounding box, in pixel indices.
    pub col_min: usize,
    pub col_max: usize,
    pub row_min: usize,
    pub row_max: usize,
    /// Whether any pixel lies on the outermost row or column of the mask.
    pub touches_border: bool,
    /// The component's first pixel in row-major order (column, row): where
    /// [`Labeller::pixels_of`] starts to list it again.
    pub seed: (usize, usize),
    sum_x: f64,
    sum_y: f64,
    sum_xx: f64,
    sum_yy: f64,
    sum_xy: f64,
}

impl Component {
    /// A component known only by its bounding box (no pixels or moments): the
    /// region searched for a disk found some other way than by labelling.
    pub fn bounding_box(col_min: usize, col_max: usize, row_min: usize, row_max: usize) -> Self {
        Self {
            pixels: (col_max + 1 - col_min) * (row_max + 1 - row_min),
            col_min,
            col_max,
            row_min,
            row_max,
            ..Self::default()
        }
    }

    /// Centroid (x, y) in image coordinates (y grows downward).
    pub fn centroid(&self) -> (f64, f64) {
        let n = self.pixels as f64;
        (self.sum_x / n, self.sum_y / n)
    }

    /// Central second moments (var x, var y, cov xy) in image coordinates.
    pub fn covariance(&self) -> (f64, f64, f64) {
        let n = self.pixels as f64;
        let (mx, my) = self.centroid();
        (
            self.sum_xx / n - mx * mx,
            self.sum_yy / n - my * my,
            self.sum_xy / n - mx * my,
        )
    }

    fn add(&mut self, c: usize, r: usize, w: usize, h: usize) {
        if self.pixels == 0 {
            (self.col_min, self.col_max, self.row_min, self.row_max) = (c, c, r, r);
            self.seed = (c, r);
        }
        self.pixels += 1;
        self.col_min = self.col_min.min(c);
        self.col_max = self.col_max.max(c);
        self.row_min = self.row_min.min(r);
        self.row_max = self.row_max.max(r);
        self.touches_border |= c == 0 || r == 0 || c + 1 == w || r + 1 == h;
        // Moments about a local origin would be better conditioned; at ≤ 4k px
        // and f64, raw sums lose < 1e-9 px² in the variance.
        let (x, y) = (c as f64 + 0.5, r as f64 + 0.5);
        self.sum_x += x;
        self.sum_y += y;
        self.sum_xx += x * x;
        self.sum_yy += y * y;
        self.sum_xy += x * y;
    }
}

/// Reusable scratch space for labelling components without allocating per frame.
#[derive(Debug, Default)]
pub(crate) struct Labeller {
    visited: Vec<bool>,
    stack: Vec<(usize, usize)>,
}

impl Labeller {
    /// All components of `mask` (row-major, `w × h`, nonzero = set) for which
    /// `keep` holds, largest first.
    pub fn components(
        &mut self,
        mask: &[bool],
        w: usize,
        h: usize,
        keep: impl Fn(&Component) -> bool,
    ) -> Vec<Component> {
        self.visited.clear();
        self.visited.resize(w * h, false);
        let mut found = Vec::new();
        for start in 0..w * h {
            if !mask[start] || self.visited[start] {
                continue;
            }
            let mut comp = Component::default();
            self.visited[start] = true;
            self.stack.push((start % w, start / w));
            while let Some((c, r)) = self.stack.pop() {
                comp.add(c, r, w, h);
                for (dc, dr) in NEIGHBOURS {
                    let (nc, nr) = (c as isize + dc, r as isize + dr);
                    if nc < 0 || nr < 0 || nc >= w as isize || nr >= h as isize {
                        continue;
                    }
                    let k = nr as usize * w + nc as usize;
                    if mask[k] && !self.visited[k] {
                        self.visited[k] = true;
                        self.stack.push((nc as usize, nr as usize));
                    }
                }
            }
            if keep(&comp) {
                found.push(comp);
            }
        }
        found.sort_by_key(|c| std::cmp::Reverse(c.pixels));
        found
    }

    /// The pixels of `mask`'s component that holds `seed` (column, row), as a
    /// row-major mask of the same size (all unset when `seed` is not set).
    pub fn pixels_of(
        &mut self,
        mask: &[bool],
        w: usize,
        h: usize,
        seed: (usize, usize),
    ) -> Vec<bool> {
        let mut member = vec![false; w * h];
        let start = seed.1 * w + seed.0;
        if seed.0 >= w || seed.1 >= h || !mask[start] {
            return member;
        }
        member[start] = true;
        self.stack.push(seed);
        while let Some((c, r)) = self.stack.pop() {
            for (dc, dr) in NEIGHBOURS {
                let (nc, nr) = (c as isize + dc, r as isize + dr);
                if nc < 0 || nr < 0 || nc >= w as isize || nr >= h as isize {
                    continue;
                }
                let k = nr as usize * w + nc as usize;
                if mask[k] && !member[k] {
                    member[k] = true;
                    self.stack.push((nc as usize, nr as usize));
                }
            }
        }
        member
    }
}

const NEIGHBOURS: [(isize, isize); 8] = [
    (-1, -1),
    (0, -1),
    (1, -1),
    (-1, 0),
    (1, 0),
    (-1, 1),
    (0, 1),
    (1, 1),
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_blobs_and_a_diagonal_neighbour() {
        // 6×4 mask: a 2×2 block touching the border, a 3-pixel diagonal chain inside.
        #[rustfmt::skip]
        let m = [
            1, 1, 0, 0, 0, 0,
            1, 1, 0, 1, 0, 0,
            0, 0, 0, 0, 1, 0,
            0, 0, 0, 0, 0, 0,
        ];
        let mask: Vec<bool> = m.iter().map(|&v| v == 1).collect();
        let comps = Labeller::default().components(&mask, 6, 4, |_| true);
        assert_eq!(comps.len(), 2);
        assert_eq!(comps[0].pixels, 4);
        assert!(comps[0].touches_border);
        assert_eq!(comps[1].pixels, 2);
        assert!(!comps[1].touches_border);
        let (cx, cy) = comps[1].centroid();
        assert_eq!((cx, cy), (4.0, 2.0));
    }
}
