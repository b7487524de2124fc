//! `shape-cubic`: signed distance maps of the drawn slices interpolated per
//! pixel by a monotone cubic (PCHIP, Fritsch & Carlson 1980) through *all*
//! drawn slices at their physical positions, so skipped slices follow the
//! curvature of the surface instead of its chords. Monotone slopes never
//! overshoot the drawn values, so no spurious object appears between two
//! drawn slices that both lack it.
use crate::shape_based::drawn_sdfs;
use crate::slices::{Plane, assemble, bracket};
use crate::{BoxReach, InterpError, Interpolator, SparseMask};
use interslice_core::Mask;

/// Monotone cubic blending of signed distance maps.
#[derive(Debug, Default, Clone, Copy)]
pub struct ShapeCubic;

/// PCHIP slope at a knot from the secants on its left (`s0` over `h0`) and
/// right (`s1` over `h1`): zero at a local extremum, else the weighted
/// harmonic mean of Fritsch & Butland.
#[inline]
pub fn pchip_slope(s0: f32, s1: f32, h0: f32, h1: f32) -> f32 {
    if s0 * s1 <= 0.0 {
        return 0.0;
    }
    let w1 = 2.0 * h1 + h0;
    let w2 = h1 + 2.0 * h0;
    (w1 + w2) / (w1 / s0 + w2 / s1)
}

/// The side of zero PCHIP's cubic between `a` and `b` is on, when both are
/// on the same side: its slopes ([`pchip_slope`]) have the secant's sign and
/// at most three times its size, so the cubic is monotone between `a` and
/// `b` (Fritsch & Carlson 1980) and the slopes need not be computed. `None`
/// when `a` and `b` differ in sign.
#[inline]
pub fn agreed_inside(a: f32, b: f32) -> Option<bool> {
    ((a < 0.0) == (b < 0.0)).then_some(a < 0.0)
}

/// The cubic Hermite basis at fraction `t` of an interval.
#[derive(Debug, Clone, Copy)]
pub struct HermiteAt {
    h00: f32,
    h10: f32,
    h01: f32,
    h11: f32,
}

impl HermiteAt {
    /// The basis at `t` in `[0, 1]`.
    pub fn new(t: f32) -> HermiteAt {
        let t2 = t * t;
        let t3 = t2 * t;
        HermiteAt {
            h00: 2.0 * t3 - 3.0 * t2 + 1.0,
            h10: t3 - 2.0 * t2 + t,
            h01: -2.0 * t3 + 3.0 * t2,
            h11: t3 - t2,
        }
    }

    /// The cubic between values `y0`, `y1` with slopes `m0`, `m1` over an
    /// interval of length `h`.
    #[inline]
    pub fn value(&self, y0: f32, y1: f32, m0: f32, m1: f32, h: f32) -> f32 {
        self.h00 * y0 + self.h10 * h * m0 + self.h01 * y1 + self.h11 * h * m1
    }

    /// The side of zero PCHIP's cubic between `a` and `b` is on here, when
    /// the values alone decide it, so that the slopes (and the neighbouring
    /// slices they are read from) need not be computed: both values on one
    /// side ([`agreed_inside`]), or, across zero, wherever the slopes fall.
    /// [`pchip_slope`]'s slopes have the secant's sign and at most three
    /// times its size, so the cubic lies in `h00 a + h01 b + (b − a)·[3 h11,
    /// 3 h10]` (`h10 ≥ 0 ≥ h11`); when that range keeps clear of zero (by a
    /// margin far above rounding) its side is the answer. `None` otherwise.
    #[inline]
    pub fn decided_inside(&self, a: f32, b: f32) -> Option<bool> {
        if let Some(inside) = agreed_inside(a, b) {
            return Some(inside);
        }
        let lin = self.h00 * a + self.h01 * b;
        let (x, y) = ((b - a) * 3.0 * self.h11, (b - a) * 3.0 * self.h10);
        let margin = 1e-4 * (a.abs() + b.abs());
        if lin + x.min(y) > margin {
            Some(false)
        } else if lin + x.max(y) < -margin {
            Some(true)
        } else {
            None
        }
    }
}

impl Interpolator for ShapeCubic {
    fn box_reach(&self) -> BoxReach {
        BoxReach::Outline
    }

    fn name(&self) -> &'static str {
        "shape-cubic"
    }

    fn description(&self) -> &'static str {
        "signed distance maps through all drawn slices by a monotone cubic (PCHIP)"
    }

    fn interpolate(&self, input: SparseMask<'_>) -> Result<Mask, InterpError> {
        input.validate()?;
        let plane = Plane::of(&input);
        let sdfs = drawn_sdfs(&input, &plane, 1)?;
        let drawn = input.drawn;
        let n = drawn.len();
        // Lengths from index differences, not from positions: the same on a
        // label's box (indices shifted) as on the whole volume.
        let len = |i: usize, j: usize| (drawn[j] - drawn[i]) as f32 * plane.slice_spacing as f32;
        assemble(&input, |s| {
            let g = bracket(drawn, s)?;
            let h = len(g, g + 1);
            let t = (s - drawn[g]) as f32 / (drawn[g + 1] - drawn[g]) as f32;
            let basis = HermiteAt::new(t);
            let y0 = sdfs[g].as_ref().expect("gap border");
            let y1 = sdfs[g + 1].as_ref().expect("gap border");
            let prev =
                (g > 0).then(|| (sdfs[g - 1].as_ref().expect("gap neighbour"), len(g - 1, g)));
            let next = (g + 2 < n).then(|| {
                (
                    sdfs[g + 2].as_ref().expect("gap neighbour"),
                    len(g + 1, g + 2),
                )
            });
            let mut out = vec![false; plane.len()];
            for p in 0..plane.len() {
                let (a, b) = (y0[p], y1[p]);
                if let Some(inside) = basis.decided_inside(a, b) {
                    out[p] = inside;
                    continue;
                }
                let sec = (b - a) / h;
                let m0 = match prev {
                    Some((yp, hp)) => pchip_slope((a - yp[p]) / hp, sec, hp, h),
                    None => sec,
                };
                let m1 = match next {
                    Some((yn, hn)) => pchip_slope(sec, (yn[p] - b) / hn, h, hn),
                    None => sec,
                };
                out[p] = basis.value(a, b, m0, m1, h) < 0.0;
            }
            Some(out)
        })
    }
}
