//! Contours → masks: rasterisation by the pixel-centre even-odd rule.
//!
//! A pixel `(u, v)` is inside a polygon when its centre `(u + 0.5, v + 0.5)`
//! is inside by the even-odd rule (docs/conventions.md). Several polygons are united:
//! each is filled by the even-odd rule on its own and the results are OR-ed,
//! so two contours of one label that overlap do not cancel each other.
//!
//! The scanline here is written for this crate because its exact crossing
//! rule matters: the crossing test at a centre row uses the half-open rule
//! `min(y0, y1) <= yc < max(y0, y1)`, so a vertex lying exactly on a centre
//! row is counted once (or twice, cancelling, at a local extremum) and
//! horizontal edges never cross. A centre lying exactly on an edge counts as
//! inside when the edge is on its right (it is outside of the crossing to its
//! left), which matches the classic crossing-number test and makes the
//! polygons traced along pixel cracks (`crate::trace`) rasterise back to their
//! mask exactly. No crate offers this convention with these guarantees.
use crate::{Axis, Contour, CoreError, Geometry, LabelVolume, Mask, SliceRef, Volume};
use rayon::prelude::*;
use std::collections::BTreeMap;

/// A run of inside pixels on one row: `u` in `start..end`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Span {
    row: u32,
    start: u32,
    end: u32,
}

/// Smallest integer `n` with `n + 0.5 >= y` (exact even where `y - 0.5`
/// would round), as i64 (saturating for huge values).
fn first_centre_at_or_after(y: f64) -> i64 {
    let mut n = (y - 0.5).ceil() as i64;
    // `y - 0.5` is exact for 0.5 <= |y| < 2^52; fix up the rare rounding case.
    while (n as f64) + 0.5 < y && n < i64::MAX / 2 {
        n += 1;
    }
    while n > i64::MIN / 2 && ((n - 1) as f64) + 0.5 >= y {
        n -= 1;
    }
    n
}

/// True when every coordinate is finite.
fn finite(poly: &[[f64; 2]]) -> bool {
    poly.iter().all(|p| p[0].is_finite() && p[1].is_finite())
}

/// Spans of one polygon (even-odd), sorted by row then start, clipped to the slice.
///
/// A polygon with fewer than 3 points or a non-finite coordinate gives nothing.
fn polygon_spans(poly: &[[f64; 2]], width: usize, height: usize, out: &mut Vec<Span>) {
    if poly.len() < 3 || width == 0 || height == 0 || !finite(poly) {
        return;
    }
    let h = height as i64;
    // (row, x of the crossing) for every edge crossing a centre row.
    let mut xs: Vec<(u32, f64)> = Vec::new();
    let n = poly.len();
    for e in 0..n {
        let a = poly[e];
        let b = poly[(e + 1) % n];
        if a[1] == b[1] {
            continue; // horizontal: never crosses a centre row
        }
        // Normalise lo -> hi so an edge gives the same x whichever way it is walked.
        let (lo, hi) = if a[1] < b[1] { (a, b) } else { (b, a) };
        // Rows with lo.y <= v + 0.5 < hi.y.
        let v0 = first_centre_at_or_after(lo[1]).max(0);
        let v1 = first_centre_at_or_after(hi[1]).min(h); // exclusive
        for v in v0..v1 {
            let yc = v as f64 + 0.5;
            let x = if hi[0] == lo[0] {
                lo[0]
            } else {
                // This form is exact whenever the true crossing is a pixel
                // centre and the inputs are moderate (e.g. dyadic) numbers.
                let x = lo[0] + (yc - lo[1]) * (hi[0] - lo[0]) / (hi[1] - lo[1]);
                if x.is_finite() {
                    x
                } else {
                    // Overflow for coordinates near f64::MAX: an overflow-free
                    // convex combination (halved so differences stay finite).
                    let t = (yc / 2.0 - lo[1] / 2.0) / (hi[1] / 2.0 - lo[1] / 2.0);
                    lo[0] * (1.0 - t) + hi[0] * t
                }
            };
            xs.push((v as u32, x));
        }
    }
    xs.sort_unstable_by(|p, q| p.0.cmp(&q.0).then(p.1.total_cmp(&q.1)));
    let w = width as i64;
    // Per row, the crossings come in pairs (a closed polygon crosses a full
    // row an even number of times); a centre x is inside when an odd number
    // of crossings is <= x, i.e. x in [x_{2m}, x_{2m+1}).
    let mut i = 0;
    while i < xs.len() {
        let row = xs[i].0;
        let mut j = i;
        while j < xs.len() && xs[j].0 == row {
            j += 1;
        }
        let crossings = &xs[i..j];
        debug_assert!(crossings.len().is_multiple_of(2));
        for pair in crossings.chunks_exact(2) {
            let s = first_centre_at_or_after(pair[0].1).clamp(0, w);
            let e = first_centre_at_or_after(pair[1].1).clamp(0, w);
            if s < e {
                out.push(Span {
                    row,
                    start: s as u32,
                    end: e as u32,
                });
            }
        }
        i = j;
    }
}

/// Pixels (row-major, `buf[u + width * v]`) whose centre is inside the union
/// of these polygons, each by the even-odd rule. Several polygons are united (OR).
///
/// Points may lie outside the slice (the result is clipped). A polygon with
/// fewer than 3 points, or with a non-finite coordinate, covers nothing here;
/// [`contours_to_labels`] and [`contours_to_mask`] reject non-finite points
/// with an error instead.
pub fn rasterize_polygons(polygons: &[&[[f64; 2]]], width: usize, height: usize) -> Vec<bool> {
    let mut buf = vec![false; width * height];
    let mut spans = Vec::new();
    for poly in polygons {
        spans.clear();
        polygon_spans(poly, width, height, &mut spans);
        for s in &spans {
            let row = s.row as usize * width;
            buf[row + s.start as usize..row + s.end as usize].fill(true);
        }
    }
    buf
}

/// Check that a contour can be rasterised into `geometry`: label not 0,
/// slice index in range, every point finite.
pub fn validate_contour(geometry: &Geometry, contour: &Contour) -> Result<(), CoreError> {
    let SliceRef { axis, index } = contour.slice;
    let len = geometry.dims[axis.dim()];
    if index >= len {
        return Err(CoreError::SliceOutOfRange { axis, index, len });
    }
    if contour.label == 0 {
        return Err(CoreError::Invalid(format!(
            "contour on slice {} has label 0 (0 is background)",
            contour.slice
        )));
    }
    if let Some(p) = contour
        .points
        .iter()
        .position(|p| !(p[0].is_finite() && p[1].is_finite()))
    {
        return Err(CoreError::Invalid(format!(
            "contour of label {} on slice {} has a non-finite point (#{p})",
            contour.label, contour.slice
        )));
    }
    Ok(())
}

/// The rasterised spans of one (label, slice): the union of its contours.
struct SliceSpans {
    label: u16,
    slice: SliceRef,
    /// Sorted by row; spans of different contours may overlap.
    spans: Vec<Span>,
}

impl SliceSpans {
    /// The spans on row `row`.
    fn row(&self, row: u32) -> &[Span] {
        let a = self.spans.partition_point(|s| s.row < row);
        let b = self.spans.partition_point(|s| s.row <= row);
        &self.spans[a..b]
    }
}

/// Validate and rasterise contours grouped by (label, slice), in parallel;
/// the result is sorted by label (then axis, index) so painting in order puts
/// higher labels over lower ones.
fn rasterise_groups<'a>(
    geometry: &Geometry,
    contours: impl Iterator<Item = &'a Contour>,
) -> Result<Vec<SliceSpans>, CoreError> {
    let mut groups: BTreeMap<(u16, SliceRef), Vec<&Contour>> = BTreeMap::new();
    for c in contours {
        validate_contour(geometry, c)?;
        groups.entry((c.label, c.slice)).or_default().push(c);
    }
    let groups: Vec<_> = groups.into_iter().collect();
    Ok(groups
        .into_par_iter()
        .map(|((label, slice), cs)| {
            let (a, b) = slice.axis.in_plane();
            let (w, h) = (geometry.dims[a], geometry.dims[b]);
            let mut spans = Vec::new();
            for c in cs {
                polygon_spans(&c.points, w, h, &mut spans);
            }
            spans.sort_unstable_by_key(|s| (s.row, s.start));
            SliceSpans {
                label,
                slice,
                spans,
            }
        })
        .collect())
}

/// Paint the groups (in their order) into `data`, in parallel over z slabs.
fn paint<T: Send + Copy>(
    geometry: &Geometry,
    groups: &[SliceSpans],
    data: &mut [T],
    value: impl Fn(u16) -> T + Sync,
) {
    let [nx, ny, _] = geometry.dims;
    data.par_chunks_mut(nx * ny)
        .enumerate()
        .for_each(|(k, slab)| {
            let k32 = k as u32;
            for g in groups {
                let val = value(g.label);
                let idx = g.slice.index;
                match g.slice.axis {
                    Axis::Z if idx == k => {
                        for s in &g.spans {
                            let row = s.row as usize * nx;
                            slab[row + s.start as usize..row + s.end as usize].fill(val);
                        }
                    }
                    Axis::Z => {}
                    // Slice y=j shows (i, k): row v = k, u = i.
                    Axis::Y => {
                        for s in g.row(k32) {
                            let row = idx * nx;
                            slab[row + s.start as usize..row + s.end as usize].fill(val);
                        }
                    }
                    // Slice x=i shows (j, k): row v = k, u = j.
                    Axis::X => {
                        for s in g.row(k32) {
                            for j in s.start as usize..s.end as usize {
                                slab[idx + nx * j] = val;
                            }
                        }
                    }
                }
            }
        });
}

/// All contours (any axes, any labels) → a label volume of `geometry`;
/// labels painted in ascending label order (higher labels overwrite lower:
/// nested structures), contours of a label on a slice united.
///
/// Errors when a contour's slice is out of range, its label is 0 or a point
/// is not finite. Contours with fewer than 3 points paint nothing.
pub fn contours_to_labels(
    geometry: &Geometry,
    contours: &[Contour],
) -> Result<LabelVolume, CoreError> {
    geometry.validate()?;
    let groups = rasterise_groups(geometry, contours.iter())?;
    let mut data = vec![0u16; geometry.len()];
    paint(geometry, &groups, &mut data, |l| l);
    Volume::from_vec(geometry.clone(), data)
}

/// One label's contours → a mask (the union of all its contours on any axis).
/// Contours of other labels are ignored (but still validated).
pub fn contours_to_mask(
    geometry: &Geometry,
    contours: &[Contour],
    label: u16,
) -> Result<Mask, CoreError> {
    geometry.validate()?;
    for c in contours {
        validate_contour(geometry, c)?;
    }
    let groups = rasterise_groups(geometry, contours.iter().filter(|c| c.label == label))?;
    let mut data = vec![false; geometry.len()];
    paint(geometry, &groups, &mut data, |_| true);
    Volume::from_vec(geometry.clone(), data)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::LengthUnit;
    use proptest::prelude::*;

    /// Independent reference: the crossing-number test at the pixel centre,
    /// with the crossing side decided by an orientation sign instead of a
    /// division (exact for the dyadic coordinates used below).
    fn brute_inside(poly: &[[f64; 2]], x: f64, y: f64) -> bool {
        if poly.len() < 3 {
            return false;
        }
        let mut inside = false;
        for e in 0..poly.len() {
            let a = poly[e];
            let b = poly[(e + 1) % poly.len()];
            if (a[1] > y) != (b[1] > y) {
                let (lo, hi) = if a[1] < b[1] { (a, b) } else { (b, a) };
                // crossing x > x  <=>  orientation of (lo, hi, p) has p on the left of the upward edge.
                let cross = (hi[0] - lo[0]) * (y - lo[1]) - (x - lo[0]) * (hi[1] - lo[1]);
                if cross > 0.0 {
                    inside = !inside;
                }
            }
        }
        inside
    }

    fn brute(polys: &[Vec<[f64; 2]>], w: usize, h: usize) -> Vec<bool> {
        let mut out = vec![false; w * h];
        for v in 0..h {
            for u in 0..w {
                let (x, y) = (u as f64 + 0.5, v as f64 + 0.5);
                out[u + w * v] = polys.iter().any(|p| brute_inside(p, x, y));
            }
        }
        out
    }

    fn refs(polys: &[Vec<[f64; 2]>]) -> Vec<&[[f64; 2]]> {
        polys.iter().map(|p| p.as_slice()).collect()
    }

    fn geom(dims: [usize; 3]) -> Geometry {
        Geometry::new(dims, [0.5, 1.0, 2.0], LengthUnit::Micrometre).unwrap()
    }

    fn contour(axis: Axis, index: usize, label: u16, points: Vec<[f64; 2]>) -> Contour {
        Contour::new(
            SliceRef { axis, index },
            label,
            points,
            "t",
            "2024-01-01T00:00:00Z",
        )
    }

    #[test]
    fn unit_square_on_pixel_corners_is_one_pixel() {
        let sq = [[1.0, 1.0], [2.0, 1.0], [2.0, 2.0], [1.0, 2.0]];
        let m = rasterize_polygons(&[&sq], 4, 3);
        let on: Vec<usize> = m.iter().enumerate().filter(|p| *p.1).map(|p| p.0).collect();
        assert_eq!(on, vec![1 + 4]);
    }

    #[test]
    fn vertex_on_a_centre_row_is_counted_once() {
        // Diamond whose left and right vertices lie exactly on row 2's centre line.
        let d = [[0.2, 2.5], [2.5, 0.2], [4.8, 2.5], [2.5, 4.8]];
        let m = rasterize_polygons(&[&d], 5, 5);
        let row2: Vec<bool> = m[10..15].to_vec();
        assert_eq!(row2, vec![true; 5]);
        assert_eq!(m, brute(&[d.to_vec()], 5, 5));
        // A spike whose tip only touches row 1's centre line: no crossing there (no fill).
        let spike = [[0.0, 0.0], [3.0, 1.5], [5.0, 0.0]];
        let m = rasterize_polygons(&[&spike], 5, 3);
        assert!(m[5..10].iter().all(|&b| !b));
    }

    #[test]
    fn centre_on_an_edge_follows_the_half_open_rule() {
        // Left edge through centres (x = 0.5): inside; right edge at x = 2.5: outside.
        let r = [[0.5, 0.0], [2.5, 0.0], [2.5, 1.0], [0.5, 1.0]];
        let m = rasterize_polygons(&[&r], 4, 1);
        assert_eq!(m, vec![true, true, false, false]);
        // Horizontal edge on a centre row: bottom edge y = 0.5 is inside, top y = 1.5 outside.
        let r = [[0.0, 0.5], [1.0, 0.5], [1.0, 1.5], [0.0, 1.5]];
        assert_eq!(rasterize_polygons(&[&r], 1, 3), vec![true, false, false]);
    }

    #[test]
    fn degenerate_and_non_finite_polygons_cover_nothing() {
        let two = [[0.0, 0.0], [5.0, 5.0]];
        let nan = [[0.0, 0.0], [f64::NAN, 5.0], [5.0, 0.0]];
        let inf = [[0.0, 0.0], [f64::INFINITY, 5.0], [5.0, 0.0]];
        let empty: [[f64; 2]; 0] = [];
        let m = rasterize_polygons(&[&two, &nan, &inf, &empty], 6, 6);
        assert!(m.iter().all(|&b| !b));
        let z = rasterize_polygons(&[&two], 0, 0);
        assert!(z.is_empty());
    }

    #[test]
    fn polygons_are_united_not_xored() {
        let a = [[0.0, 0.0], [3.0, 0.0], [3.0, 1.0], [0.0, 1.0]];
        let b = [[1.0, 0.0], [4.0, 0.0], [4.0, 1.0], [1.0, 1.0]];
        assert_eq!(
            rasterize_polygons(&[&a, &b], 5, 1),
            vec![true, true, true, true, false]
        );
        // One self-overlapping polygon (a square walked twice) is even-odd: a hole.
        let twice = [
            [0.0, 0.0],
            [2.0, 0.0],
            [2.0, 1.0],
            [0.0, 1.0],
            [0.0, 0.0],
            [2.0, 0.0],
            [2.0, 1.0],
            [0.0, 1.0],
        ];
        assert!(rasterize_polygons(&[&twice], 3, 1).iter().all(|&b| !b));
    }

    #[test]
    fn polygon_far_outside_is_clipped() {
        let big = [[-1e9, -1e9], [1e9, -1e9], [1e9, 1e9], [-1e9, 1e9]];
        assert!(rasterize_polygons(&[&big], 7, 3).iter().all(|&b| b));
        let huge = [
            [-1e300, -1e300],
            [1e300, -1e300],
            [1e300, 1e300],
            [-1e300, 1e300],
        ];
        assert!(rasterize_polygons(&[&huge], 2, 2).iter().all(|&b| b));
        let tri = [[-1e300, -1e300], [1e300, -1e300], [0.0, 1e300]];
        assert!(rasterize_polygons(&[&tri], 3, 3).iter().all(|&b| b));
        let tri = [[-1.7e308, -1.7e308], [1.7e308, -1.7e308], [0.0, 1.7e308]];
        assert!(rasterize_polygons(&[&tri], 3, 3).iter().all(|&b| b));
    }

    #[test]
    fn labels_paint_in_ascending_order_on_every_axis() {
        let g = geom([6, 5, 4]);
        let full = |w: f64, h: f64| vec![[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]];
        // Label 2 on z=1 (whole slice) listed before label 1 on x=2 (whole slice).
        let cs = vec![
            contour(Axis::Z, 1, 2, full(6.0, 5.0)),
            contour(Axis::X, 2, 1, full(5.0, 4.0)),
        ];
        let lv = contours_to_labels(&g, &cs).unwrap();
        for k in 0..4 {
            for j in 0..5 {
                for i in 0..6 {
                    let want = if k == 1 {
                        2
                    } else if i == 2 {
                        1
                    } else {
                        0
                    };
                    assert_eq!(lv.get(i, j, k), want, "voxel {i},{j},{k}");
                }
            }
        }
        let m = contours_to_mask(&g, &cs, 1).unwrap();
        assert_eq!(m.data().iter().filter(|&&b| b).count(), 5 * 4);
        assert!(m.get(2, 0, 1));
        // y slice: label 3 on y=4, a unit square at pixel (u=1, v=3) -> voxel (1, 4, 3).
        let cs = vec![contour(
            Axis::Y,
            4,
            3,
            vec![[1.0, 3.0], [2.0, 3.0], [2.0, 4.0], [1.0, 4.0]],
        )];
        let lv = contours_to_labels(&g, &cs).unwrap();
        assert_eq!(lv.label_counts(), vec![(3, 1)]);
        assert_eq!(lv.get(1, 4, 3), 3);
    }

    #[test]
    fn bad_contours_are_errors() {
        let g = geom([4, 4, 4]);
        let sq = vec![[0.0, 0.0], [2.0, 0.0], [2.0, 2.0]];
        let out = contour(Axis::Y, 4, 1, sq.clone());
        assert!(matches!(
            contours_to_labels(&g, std::slice::from_ref(&out)),
            Err(CoreError::SliceOutOfRange {
                index: 4,
                len: 4,
                ..
            })
        ));
        assert!(contours_to_mask(&g, &[out], 2).is_err());
        let nan = contour(Axis::Z, 0, 1, vec![[0.0, 0.0], [f64::NAN, 1.0], [1.0, 1.0]]);
        assert!(contours_to_labels(&g, &[nan]).is_err());
        let zero = contour(Axis::Z, 0, 0, sq);
        assert!(contours_to_labels(&g, &[zero]).is_err());
    }

    /// Dyadic coordinates (multiples of 1/4) around and beyond a small slice:
    /// vertices and crossings land exactly on centre rows, centres and
    /// pixel corners, the hard cases of the half-open rule.
    fn dyadic_poly() -> impl Strategy<Value = Vec<[f64; 2]>> {
        prop::collection::vec((-8i32..56, -8i32..48), 0..12).prop_map(|v| {
            v.into_iter()
                .map(|(a, b)| [a as f64 / 4.0, b as f64 / 4.0])
                .collect()
        })
    }

    fn float_poly() -> impl Strategy<Value = Vec<[f64; 2]>> {
        prop::collection::vec((-3.0f64..15.0, -3.0f64..13.0), 3..16)
            .prop_map(|v| v.into_iter().map(|(a, b)| [a, b]).collect())
    }

    proptest! {
        #[test]
        fn matches_brute_force_on_dyadic_polygons(polys in prop::collection::vec(dyadic_poly(), 1..4), w in 1usize..13, h in 1usize..11) {
            prop_assert_eq!(rasterize_polygons(&refs(&polys), w, h), brute(&polys, w, h));
        }

        #[test]
        fn matches_brute_force_on_float_polygons(polys in prop::collection::vec(float_poly(), 1..3), w in 1usize..13, h in 1usize..11) {
            prop_assert_eq!(rasterize_polygons(&refs(&polys), w, h), brute(&polys, w, h));
        }

        #[test]
        fn volume_slices_match_brute_force_on_every_axis(
            axis_n in 0usize..3, label in 1u16..4,
            polys in prop::collection::vec(dyadic_poly(), 1..3),
            dims in (1usize..9, 1usize..9, 1usize..9), idx in 0usize..9,
        ) {
            let g = geom([dims.0, dims.1, dims.2]);
            let axis = Axis::ALL[axis_n];
            let index = idx % g.dims[axis.dim()];
            let cs: Vec<Contour> = polys.iter().map(|p| contour(axis, index, label, p.clone())).collect();
            let lv = contours_to_labels(&g, &cs).unwrap();
            let m = contours_to_mask(&g, &cs, label).unwrap();
            let (a, b) = axis.in_plane();
            let (w, h) = (g.dims[a], g.dims[b]);
            let want = brute(&polys, w, h);
            for k in 0..g.dims[2] { for j in 0..g.dims[1] { for i in 0..g.dims[0] {
                let (s, u, v) = axis.split([i, j, k]);
                let inside = s == index && want[u + w * v];
                prop_assert_eq!(lv.get(i, j, k), if inside { label } else { 0 });
                prop_assert_eq!(m.get(i, j, k), inside);
            }}}
        }
    }
}
