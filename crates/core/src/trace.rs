//! Tracing the boundary of a 2D mask into closed polygons.
//!
//! [`mask_polygons`] follows the *cracks* between pixels: every polygon edge
//! lies on a pixel edge and every vertex on a pixel corner, so the even-odd
//! rasterisation of the polygons (pixel centres) gives back the mask exactly.
//! Interpolators use it to turn a drawn slice into contours, and the server to
//! show an interpolated mask as contours. Written here because the crack
//! following with the connectivity rule and the exactness guarantee is a few
//! dozen lines and no crate offers it for this coordinate convention.

/// Direction of a crack edge: 0 = +u, 1 = +v, 2 = -u, 3 = -v.
const STEP: [(i64, i64); 4] = [(1, 0), (0, 1), (-1, 0), (0, -1)];

/// Closed polygons (outer boundaries and holes) of a row-major mask
/// (`mask[u + width * v]`), in continuous `(u, v)` pixel coordinates.
///
/// Vertices are pixel corners (integers), consecutive collinear vertices are
/// merged, and the last vertex connects back to the first (not repeated).
/// Foreground is on the left when walking a polygon in a frame where u points
/// right and v points up, so outer boundaries run counter-clockwise in that
/// frame and holes clockwise. Foreground is 4-connected: two pixels touching
/// only at a corner get separate polygons. The even-odd rule applied to the
/// pixel centres reproduces `mask` exactly.
///
/// Panics if `mask.len() != width * height` (a programming error).
pub fn mask_polygons(mask: &[bool], width: usize, height: usize) -> Vec<Vec<[f64; 2]>> {
    assert_eq!(
        mask.len(),
        width * height,
        "mask length must be width * height"
    );
    let cw = width + 1;
    let at = |u: i64, v: i64| -> bool {
        u >= 0
            && v >= 0
            && (u as usize) < width
            && (v as usize) < height
            && mask[u as usize + width * v as usize]
    };
    // Outgoing crack edges per corner, one bit per direction.
    let mut out = vec![0u8; cw * (height + 1)];
    let corner = |u: usize, v: usize| u + cw * v;
    let mut any = false;
    for v in 0..height {
        for u in 0..width {
            if !mask[u + width * v] {
                continue;
            }
            let (a, b) = (u as i64, v as i64);
            if !at(a, b - 1) {
                out[corner(u, v)] |= 1 << 0; // (a,b) -> (a+1,b)
                any = true;
            }
            if !at(a + 1, b) {
                out[corner(u + 1, v)] |= 1 << 1; // (a+1,b) -> (a+1,b+1)
                any = true;
            }
            if !at(a, b + 1) {
                out[corner(u + 1, v + 1)] |= 1 << 2; // (a+1,b+1) -> (a,b+1)
                any = true;
            }
            if !at(a - 1, b) {
                out[corner(u, v + 1)] |= 1 << 3; // (a,b+1) -> (a,b)
                any = true;
            }
        }
    }
    let mut polygons = Vec::new();
    if !any {
        return polygons;
    }
    for start in 0..out.len() {
        while out[start] != 0 {
            let start_dir = out[start].trailing_zeros() as usize;
            let (su, sv) = ((start % cw) as i64, (start / cw) as i64);
            let mut pts: Vec<[f64; 2]> = Vec::new();
            let (mut cu, mut cv) = (su, sv);
            let mut dir = start_dir;
            let mut first = true;
            loop {
                let c = cu as usize + cw * cv as usize;
                // Prefer a left turn, then straight, then right: with foreground
                // on the left this keeps diagonal pixels apart (4-connectivity).
                let next = if first {
                    start_dir
                } else {
                    let mut chosen = None;
                    for turn in [1usize, 0, 3] {
                        let d = (dir + turn) % 4;
                        if out[c] & (1 << d) != 0 {
                            chosen = Some(d);
                            break;
                        }
                    }
                    // Every corner has as many incoming as outgoing edges, so
                    // a walk that entered a corner can always leave it.
                    chosen.expect("crack boundary is closed")
                };
                if !first && c == start && next == start_dir {
                    // The start edge stays set until here so that the walk
                    // can recognise it by the turn rule when it comes back.
                    out[c] &= !(1 << next);
                    break;
                }
                if first || next != dir {
                    pts.push([cu as f64, cv as f64]);
                }
                if !first {
                    out[c] &= !(1 << next);
                }
                first = false;
                dir = next;
                cu += STEP[dir].0;
                cv += STEP[dir].1;
            }
            // The walk closes on the start direction, so the start vertex is a
            // real corner and no collinear vertex remains.
            polygons.push(pts);
        }
    }
    polygons
}

/// Shoelace area of a closed polygon: positive for the counter-clockwise
/// (u right, v up) outer boundaries of [`mask_polygons`], negative for its
/// holes, so `signed_area(p) > 0.0` picks the outer boundaries.
pub fn signed_area(p: &[[f64; 2]]) -> f64 {
    let n = p.len();
    (0..n)
        .map(|a| {
            let (q, r) = (p[a], p[(a + 1) % n]);
            q[0] * r[1] - r[0] * q[1]
        })
        .sum::<f64>()
        / 2.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Brute-force even-odd test of a point against all polygons.
    fn inside(polys: &[Vec<[f64; 2]>], x: f64, y: f64) -> bool {
        let mut c = false;
        for p in polys {
            let n = p.len();
            for i in 0..n {
                let [x1, y1] = p[i];
                let [x2, y2] = p[(i + 1) % n];
                if (y1 > y) != (y2 > y) {
                    let xi = x1 + (y - y1) * (x2 - x1) / (y2 - y1);
                    if x < xi {
                        c = !c;
                    }
                }
            }
        }
        c
    }

    fn rasterise(polys: &[Vec<[f64; 2]>], w: usize, h: usize) -> Vec<bool> {
        let mut m = vec![false; w * h];
        for v in 0..h {
            for u in 0..w {
                m[u + w * v] = inside(polys, u as f64 + 0.5, v as f64 + 0.5);
            }
        }
        m
    }

    fn mask_from(rows: &[&str]) -> (Vec<bool>, usize, usize) {
        let h = rows.len();
        let w = rows[0].len();
        let m = rows
            .iter()
            .flat_map(|r| r.chars().map(|c| c == '#'))
            .collect();
        (m, w, h)
    }

    #[test]
    fn single_pixel_is_a_unit_square() {
        let p = mask_polygons(&[true], 1, 1);
        assert_eq!(
            p,
            vec![vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]]
        );
    }

    #[test]
    fn empty_mask_has_no_polygons() {
        assert!(mask_polygons(&[false; 12], 4, 3).is_empty());
    }

    #[test]
    fn rectangle_has_four_vertices() {
        let (m, w, h) = mask_from(&["....", ".##.", ".##.", "...."]);
        let p = mask_polygons(&m, w, h);
        assert_eq!(p.len(), 1);
        assert_eq!(p[0], vec![[1.0, 1.0], [3.0, 1.0], [3.0, 3.0], [1.0, 3.0]]);
    }

    #[test]
    fn ring_gives_outer_and_hole() {
        let (m, w, h) = mask_from(&["###", "#.#", "###"]);
        let p = mask_polygons(&m, w, h);
        assert_eq!(p.len(), 2);
        let lens: Vec<usize> = p.iter().map(|q| q.len()).collect();
        assert_eq!(lens, vec![4, 4]);
        assert_eq!(rasterise(&p, w, h), m);
    }

    #[test]
    fn diagonal_pixels_are_separate_polygons() {
        let (m, w, h) = mask_from(&["#.", ".#"]);
        let p = mask_polygons(&m, w, h);
        assert_eq!(p.len(), 2);
        assert!(p.iter().all(|q| q.len() == 4));
        // The hole of a diagonal "checker" ring: background touching diagonally.
        let (m, w, h) = mask_from(&[".#.", "#.#", ".#."]);
        let p = mask_polygons(&m, w, h);
        assert_eq!(p.len(), 4);
        assert_eq!(rasterise(&p, w, h), m);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]
        #[test]
        fn even_odd_rasterisation_reproduces_the_mask(
            (w, h, bits) in (1usize..14, 1usize..14)
                .prop_flat_map(|(w, h)| (Just(w), Just(h), proptest::collection::vec(any::<bool>(), w * h)))
        ) {
            let polys = mask_polygons(&bits, w, h);
            prop_assert_eq!(rasterise(&polys, w, h), bits.clone());
            // Vertices on corners, no collinear consecutive vertices, edges axis-aligned.
            for p in &polys {
                prop_assert!(p.len() >= 4);
                let n = p.len();
                for i in 0..n {
                    let a = p[i];
                    let b = p[(i + 1) % n];
                    let c = p[(i + 2) % n];
                    prop_assert!(a[0].fract() == 0.0 && a[1].fract() == 0.0);
                    prop_assert!(a[0] == b[0] || a[1] == b[1]);
                    let cross = (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0]);
                    prop_assert!(cross != 0.0);
                }
            }
            // Area: outer minus holes equals the pixel count.
            let area: f64 = polys.iter().map(|p| signed_area(p)).sum();
            prop_assert_eq!(area, bits.iter().filter(|&&b| b).count() as f64);
        }
    }
}
