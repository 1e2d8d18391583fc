//! 1-D minimisation: golden-section search on a bracket, and the bracketing of a
//! minimum by golden steps downhill.

/// The golden ratio's conjugate (√5 − 1)/2: the share of a bracket an inner point
/// of a golden-section search lies from its far end.
const INVERSE_GOLDEN: f64 = 0.618_033_988_749_894_9;

/// When a golden-section search stops.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Stop {
    /// After this many steps (the bracket shrinks to 0.618^steps of its width).
    Steps(usize),
    /// When the bracket is at most this wide.
    Width(f64),
}

/// The last bracket [lo, hi] of a golden-section search, its two inner points
/// c < d and their values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GoldenSection {
    pub lo: f64,
    pub hi: f64,
    pub c: (f64, f64),
    pub d: (f64, f64),
}

impl GoldenSection {
    /// The bracket's midpoint.
    pub fn midpoint(&self) -> f64 {
        0.5 * (self.lo + self.hi)
    }

    /// The inner point with the lower value (c on a tie), and that value.
    pub fn best(&self) -> (f64, f64) {
        if self.c.1 <= self.d.1 { self.c } else { self.d }
    }
}

/// Golden-section search for the minimum of `f`, unimodal on [a, b]: each step
/// keeps the part of the bracket on the side of the inner point with the lower
/// value (the upper part on a tie) and evaluates `f` once, until `stop`.
pub fn golden_section(
    mut f: impl FnMut(f64) -> f64,
    mut a: f64,
    mut b: f64,
    stop: Stop,
) -> GoldenSection {
    let r = INVERSE_GOLDEN;
    let (mut c, mut d) = (b - r * (b - a), a + r * (b - a));
    let (mut fc, mut fd) = (f(c), f(d));
    let mut steps = 0;
    while match stop {
        Stop::Steps(n) => steps < n,
        Stop::Width(width) => b - a > width,
    } {
        if fc < fd {
            (b, d, fd) = (d, c, fc);
            c = b - r * (b - a);
            fc = f(c);
        } else {
            (a, c, fc) = (c, d, fd);
            d = a + r * (b - a);
            fd = f(d);
        }
        steps += 1;
    }
    GoldenSection {
        lo: a,
        hi: b,
        c: (c, fc),
        d: (d, fd),
    }
}

/// Three points (x, f(x)) around a minimum of `f`, the middle one the lowest:
/// from `x0` and `x0 + step`, steps grown by the golden ratio go downhill, at most
/// `max_steps` times (after which the last three points are returned as they are).
pub fn bracket_minimum(
    mut f: impl FnMut(f64) -> f64,
    x0: f64,
    step: f64,
    max_steps: usize,
) -> [(f64, f64); 3] {
    let grow = 1.0 + INVERSE_GOLDEN;
    let (mut a, mut fa) = (x0, f(x0));
    let (mut b, mut fb) = (x0 + step, f(x0 + step));
    if fb > fa {
        std::mem::swap(&mut a, &mut b);
        std::mem::swap(&mut fa, &mut fb);
    }
    let mut c = b + grow * (b - a);
    let mut fc = f(c);
    let mut steps = 0;
    while fc < fb && steps < max_steps {
        (a, fa, b, fb) = (b, fb, c, fc);
        c = b + grow * (b - a);
        fc = f(c);
        steps += 1;
    }
    [(a, fa), (b, fb), (c, fc)]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The constant is (√5 − 1)/2 to the last bit.
    #[test]
    fn the_inverse_golden_ratio() {
        assert_eq!(INVERSE_GOLDEN, 0.5 * (5f64.sqrt() - 1.0));
    }

    /// A parabola's vertex, found to the bracket's width and by a fixed number of
    /// steps (0.618^60 of the bracket: 2e-12), from a bracket found downhill. A
    /// minimum is located to about √ε ≈ 1.5e-8 of the function's scale only: closer
    /// to it, f differs from its least value by less than its rounding.
    #[test]
    fn golden_section_finds_a_parabolas_vertex() {
        let f = |x: f64| (x - 1.234).powi(2) + 0.5;
        let by_width = golden_section(f, -3.0, 4.0, Stop::Width(1e-9));
        assert!((by_width.midpoint() - 1.234).abs() < 1e-7);
        let by_steps = golden_section(f, -3.0, 4.0, Stop::Steps(60));
        assert!((by_steps.best().0 - 1.234).abs() < 1e-7);
        let [(a, fa), (b, fb), (c, fc)] = bracket_minimum(f, -10.0, 0.5, 40);
        assert!(fb <= fa && fb <= fc, "{fa} {fb} {fc}");
        assert!(a.min(c) < 1.234 && 1.234 < a.max(c));
        assert!((b - 1.234).abs() < (a - 1.234).abs().max((c - 1.234).abs()));
    }
}
