//! Connected regions: the union-find every grouping in the workspace uses,
//! and connected components, hole filling and "the whole structure of a
//! label" on 2D slices (row-major `w × h`, index `u + w * v`).
//!
//! The union-find is `petgraph`'s (union by rank, path halving): the callers
//! only ever ask which elements share a class, never which one is the root,
//! so any correct union-find gives them the same result.
//!
//! The 3D counterparts (components on runs of voxels, 3D hole filling) are in
//! [`crate::morph`].
use crate::morph::{ComponentRuns, Connectivity, label_components};
use crate::{LabelVolume, Mask, Volume};

pub use petgraph::unionfind::UnionFind;

/// The in-slice neighbours of pixel `i` of a `w × h` slice, in row order
/// (the row above first, left to right, then the pixel's own row, then the
/// row below): 4 for [`Connectivity::Face`], 8 for [`Connectivity::Full`].
pub fn neighbours_2d(
    i: usize,
    w: usize,
    h: usize,
    conn: Connectivity,
) -> impl Iterator<Item = usize> {
    // Written out into an array rather than chained adapters (a flat map
    // with a filter): the image method's separation asks this of every
    // pixel of its band, where the chain was a tenth of its time.
    let (u, v) = (i % w, i / w);
    let full = conn == Connectivity::Full;
    let mut out = [0usize; 8];
    let mut n = 0;
    for vv in [v.wrapping_sub(1), v, v + 1] {
        if vv >= h {
            continue;
        }
        for uu in [u.wrapping_sub(1), u, u + 1] {
            if uu >= w || (uu == u && vv == v) || (!full && uu != u && vv != v) {
                continue;
            }
            out[n] = uu + w * vv;
            n += 1;
        }
    }
    out.into_iter().take(n)
}

/// Connected components of the pixels where `mask` is true, one after the
/// other in scan order of their first pixel. Returns the component of every
/// pixel (0 off the mask, component `r` (0-based) labelled `r + 1`).
///
/// `visit(r, p)` is called once for every pixel `p` of the mask, component by
/// component; within a component the pixels come depth-first from its first
/// pixel, neighbours in the order of [`neighbours_2d`] (callers that grow
/// regions further from this order rely on it being fixed).
pub fn flood_2d(
    mask: &[bool],
    w: usize,
    h: usize,
    conn: Connectivity,
    mut visit: impl FnMut(u32, usize),
) -> Vec<u32> {
    debug_assert_eq!(mask.len(), w * h);
    let mut labels = vec![0u32; mask.len()];
    // Pixels with their (u, v), so that no pixel costs a division; the
    // neighbours are visited in the order of `neighbours_2d`, written out.
    let mut stack: Vec<(usize, usize, usize)> = Vec::new();
    let mut next = 0u32;
    let full = conn == Connectivity::Full;
    for start in 0..mask.len() {
        if !mask[start] || labels[start] != 0 {
            continue;
        }
        next += 1;
        labels[start] = next;
        stack.push((start, start % w, start / w));
        while let Some((p, u, v)) = stack.pop() {
            visit(next - 1, p);
            for dv in [-1isize, 0, 1] {
                let Some(vv) = v.checked_add_signed(dv).filter(|&y| y < h) else {
                    continue;
                };
                for du in [-1isize, 0, 1] {
                    if (du == 0 && dv == 0) || (!full && du != 0 && dv != 0) {
                        continue;
                    }
                    let Some(uu) = u.checked_add_signed(du).filter(|&x| x < w) else {
                        continue;
                    };
                    let q = uu + w * vv;
                    if mask[q] && labels[q] == 0 {
                        labels[q] = next;
                        stack.push((q, uu, vv));
                    }
                }
            }
        }
    }
    labels
}

/// Connected components of `mask`: labels as [`flood_2d`] gives them and the
/// pixel count of each (`sizes[label - 1]`), found on runs
/// ([`ComponentRuns`]) rather than pixel by pixel.
pub fn label_2d(mask: &[bool], w: usize, h: usize, conn: Connectivity) -> (Vec<u32>, Vec<usize>) {
    let c = ComponentRuns::of(mask, [w, h, 1], conn);
    (c.ids(), c.sizes().into_iter().map(|s| s as usize).collect())
}

/// The holes of `mask`: the pixels off the mask whose component (connected by
/// `background`) does not touch the border of the slice and passes `keep`,
/// which sees the pixels of one component.
///
/// [`Connectivity::Full`] (8-connected background) leaves two foreground
/// pixels that touch only at a corner apart, as a 4-connected inside does.
pub fn holes_2d(
    mask: &[bool],
    w: usize,
    h: usize,
    background: Connectivity,
    mut keep: impl FnMut(&[usize]) -> bool,
) -> Vec<bool> {
    let off: Vec<bool> = mask.iter().map(|&m| !m).collect();
    let mut comps: Vec<Vec<usize>> = Vec::new();
    flood_2d(&off, w, h, background, |r, p| {
        if r as usize == comps.len() {
            comps.push(Vec::new());
        }
        comps[r as usize].push(p);
    });
    let mut hole = vec![false; mask.len()];
    for comp in comps {
        let open = comp.iter().any(|&p| {
            let (u, v) = (p % w, p / w);
            u == 0 || v == 0 || u + 1 == w || v + 1 == h
        });
        if !open && keep(&comp) {
            for p in comp {
                hole[p] = true;
            }
        }
    }
    hole
}

/// The whole structure of `label` in a painted label volume: the voxels of
/// `label` together with every region they enclose that holds only higher
/// labels. This is the one definition used wherever a label is compared with
/// what a person traced (the drawn slices before interpolation, the ground
/// truth of `variability`).
///
/// Label volumes here are painted in ascending label order, so an inner
/// structure overwrites the one containing it (a nucleus inside its cell,
/// nucleoli inside their nucleus). A tracer outlines the whole cell, nucleus
/// included; this gives back that outline's inside. A region of background
/// or of a lower label stays out: it was left out on purpose (an inner
/// contour, as the server keeps it for a tracing).
///
/// A region is a component of the voxels off `label`, connected by
/// `background`, that touches no face of the volume; as in
/// [`crate::morph::fill_holes`], only dimensions longer than one voxel have
/// faces, so a single slice (`nz = 1`) is treated as a 2D image.
pub fn whole_structure(labels: &LabelVolume, label: u16, background: Connectivity) -> Mask {
    let mask = labels.mask_of(label);
    if !labels.data().iter().any(|&v| v > label) {
        return mask;
    }
    let off = mask.map(|v| !v);
    let (ids, sizes) = label_components(&off, background);
    // Per region: open (touches a face), or holding a label <= `label`.
    let mut out_of_reach = vec![false; sizes.len()];
    let [nx, ny, nz] = labels.dims();
    let face = |i: usize, n: usize| n > 1 && (i == 0 || i + 1 == n);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let n = i + nx * (j + ny * k);
                let id = ids.data()[n];
                if id == 0 {
                    continue;
                }
                if face(i, nx) || face(j, ny) || face(k, nz) || labels.data()[n] <= label {
                    out_of_reach[id as usize - 1] = true;
                }
            }
        }
    }
    let data = mask
        .data()
        .iter()
        .zip(ids.data())
        .map(|(&m, &id)| m || (id > 0 && !out_of_reach[id as usize - 1]))
        .collect();
    Volume::from_vec(labels.geometry().clone(), data).expect("same geometry")
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Components by repeated union of neighbouring pixels (the reference).
    fn union_components(mask: &[bool], w: usize, h: usize, conn: Connectivity) -> Vec<usize> {
        let mut uf: UnionFind<usize> = UnionFind::new(mask.len());
        for p in 0..mask.len() {
            if mask[p] {
                for q in neighbours_2d(p, w, h, conn) {
                    if mask[q] {
                        uf.union(p, q);
                    }
                }
            }
        }
        (0..mask.len()).map(|p| uf.find_mut(p)).collect()
    }

    #[test]
    fn neighbours_in_row_order() {
        let n: Vec<usize> = neighbours_2d(4, 3, 3, Connectivity::Full).collect();
        assert_eq!(n, vec![0, 1, 2, 3, 5, 6, 7, 8]);
        let n: Vec<usize> = neighbours_2d(4, 3, 3, Connectivity::Face).collect();
        assert_eq!(n, vec![1, 3, 5, 7]);
        let n: Vec<usize> = neighbours_2d(0, 3, 3, Connectivity::Full).collect();
        assert_eq!(n, vec![1, 3, 4]);
    }

    #[test]
    fn diagonal_pixels_join_only_when_fully_connected() {
        let m = [true, false, false, true];
        assert_eq!(
            label_2d(&m, 2, 2, Connectivity::Face),
            (vec![1, 0, 0, 2], vec![1, 1])
        );
        assert_eq!(
            label_2d(&m, 2, 2, Connectivity::Full),
            (vec![1, 0, 0, 1], vec![2])
        );
    }

    #[test]
    fn ring_hole_is_filled_only_with_higher_labels() {
        // 5 x 5 x 1: label 1 ring, centre 2 (filled) or 0 (kept a hole).
        let g = crate::Geometry::new([5, 5, 1], [1.0; 3], crate::LengthUnit::default()).unwrap();
        let mut l = vec![0u16; 25];
        for v in 1..4 {
            for u in 1..4 {
                l[u + 5 * v] = 1;
            }
        }
        l[12] = 2;
        let vol = Volume::from_vec(g.clone(), l.clone()).unwrap();
        let s = whole_structure(&vol, 1, Connectivity::Full);
        assert_eq!(s.data().iter().filter(|&&b| b).count(), 9);
        l[12] = 0;
        let vol = Volume::from_vec(g, l).unwrap();
        let s = whole_structure(&vol, 1, Connectivity::Full);
        assert_eq!(s.data().iter().filter(|&&b| b).count(), 8);
        assert!(!s.data()[12]);
    }

    #[test]
    fn a_cell_holds_its_nucleus_in_3d_but_not_an_empty_cavity() {
        // 7^3: cell (1) shell, nucleus (2) in the centre, then a cavity of 0.
        let g = crate::Geometry::new([7, 7, 7], [1.0; 3], crate::LengthUnit::default()).unwrap();
        let mut vol: LabelVolume = Volume::zeros(g);
        for k in 1..6 {
            for j in 1..6 {
                for i in 1..6 {
                    vol.set(
                        i,
                        j,
                        k,
                        if (2..5).contains(&i) && (2..5).contains(&j) && (2..5).contains(&k) {
                            2
                        } else {
                            1
                        },
                    );
                }
            }
        }
        let cell = whole_structure(&vol, 1, Connectivity::Face);
        assert_eq!(cell.data().iter().filter(|&&b| b).count(), 125);
        // A cavity touching only the nucleus region makes it a mixed region: kept out.
        vol.set(3, 3, 3, 0);
        let cell = whole_structure(&vol, 1, Connectivity::Face);
        assert_eq!(cell.data().iter().filter(|&&b| b).count(), 125 - 27);
        // The nucleus itself is whole either way (nothing higher inside).
        assert_eq!(
            whole_structure(&vol, 2, Connectivity::Face)
                .data()
                .iter()
                .filter(|&&b| b)
                .count(),
            26
        );
    }

    proptest! {
        #[test]
        fn flood_matches_union_find(w in 1usize..9, h in 1usize..9, bits in any::<u64>(), full in any::<bool>()) {
            let conn = if full { Connectivity::Full } else { Connectivity::Face };
            let mask: Vec<bool> = (0..w * h).map(|i| bits >> (i % 64) & 1 == 1).collect();
            let (labels, sizes) = label_2d(&mask, w, h, conn);
            let root = union_components(&mask, w, h, conn);
            prop_assert_eq!(sizes.iter().sum::<usize>(), mask.iter().filter(|&&b| b).count());
            for p in 0..mask.len() {
                prop_assert_eq!(labels[p] == 0, !mask[p]);
                for q in 0..mask.len() {
                    if mask[p] && mask[q] {
                        prop_assert_eq!(labels[p] == labels[q], root[p] == root[q]);
                    }
                }
            }
            // Numbered in scan order of first pixels.
            let mut seen = 0u32;
            for &l in &labels {
                if l > seen {
                    prop_assert_eq!(l, seen + 1);
                    seen = l;
                }
            }
            // Visited depth-first, neighbours in the order of `neighbours_2d`.
            let mut order = Vec::new();
            flood_2d(&mask, w, h, conn, |r, p| order.push((r, p)));
            let mut expected = Vec::new();
            let mut done = vec![false; mask.len()];
            for start in 0..mask.len() {
                if !mask[start] || done[start] {
                    continue;
                }
                let r = labels[start] - 1;
                done[start] = true;
                let mut stack = vec![start];
                while let Some(p) = stack.pop() {
                    expected.push((r, p));
                    for q in neighbours_2d(p, w, h, conn) {
                        if mask[q] && !done[q] {
                            done[q] = true;
                            stack.push(q);
                        }
                    }
                }
            }
            prop_assert_eq!(order, expected);
        }

        #[test]
        fn holes_do_not_touch_the_border(w in 1usize..9, h in 1usize..9, bits in any::<u64>()) {
            let mask: Vec<bool> = (0..w * h).map(|i| bits >> (i % 64) & 1 == 1).collect();
            let hole = holes_2d(&mask, w, h, Connectivity::Full, |_| true);
            for p in 0..mask.len() {
                let (u, v) = (p % w, p / w);
                if u == 0 || v == 0 || u + 1 == w || v + 1 == h {
                    prop_assert!(!hole[p]);
                }
                prop_assert!(!(hole[p] && mask[p]));
                // A hole pixel has no open neighbour outside the mask.
                if hole[p] {
                    for q in neighbours_2d(p, w, h, Connectivity::Full) {
                        prop_assert!(mask[q] || hole[q]);
                    }
                }
            }
        }
    }
}
