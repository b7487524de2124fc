//! The cell offsets of a slab in the order the search of the border
//! distances visits them ([`super::surface`]): by ascending
//! `sx²·Δi² + sy²·Δj²`, which bounds the squared distance of every voxel of
//! the cell's column from below.
//!
//! The search keeps the least `sx²·Δi² + (sy²·Δj² + (sz·count)²)` over the
//! cells it visits and stops at the first cell whose bound reaches it: on the
//! dense, close borders of a segmentation against its ground truth that is a
//! few dozen cells a query, read from a precomputed table rather than found
//! row by row.

/// About the most cells of a [`Disc`]: a disc of 30 voxels' radius.
pub(super) const MAX_CELLS: f64 = 3000.0;

/// Cells the search visits together: it checks its bound once a group.
pub(super) const GROUP: usize = 4;

/// One cell offset of a [`Disc`], with the terms of its squared distance.
#[derive(Debug, Clone, Copy)]
pub(super) struct Cell {
    /// Linear offset in a slab.
    pub(super) lin: isize,
    /// Offset along x and y.
    pub(super) d: [i32; 2],
    /// `sx²·Δi²`.
    pub(super) x: f64,
    /// `sy²·Δj²`.
    pub(super) fy: f64,
    /// `x + fy`: no voxel of the column can be nearer than this.
    pub(super) lb: f64,
}

/// The cell offsets of a slab around a query, by ascending `sx²·Δi² + sy²·Δj²`:
/// the order in which the search of the slice counts visits them, stopping
/// at the first cell that cannot beat the best value so far.
#[derive(Debug, Clone)]
pub(super) struct Disc {
    cells: Vec<Cell>,
    /// Every offset with `lb` up to this is in `cells`.
    pub(super) limit: f64,
}

impl Disc {
    /// The disc of about `max_cells` cells for slabs of `cx × cy` cells of
    /// spacing² `sx2 × sy2`.
    pub(super) fn new(cx: usize, cy: usize, sx2: f64, sy2: f64, max_cells: f64) -> Disc {
        let limit = max_cells * (sx2 * sy2).sqrt() / std::f64::consts::PI;
        let mut cells = Vec::new();
        for b in 0..cy {
            let fy = sy2 * b as f64 * b as f64;
            if fy > limit {
                break;
            }
            for a in 0..cx {
                let x = sx2 * a as f64 * a as f64;
                let lb = x + fy;
                if lb > limit {
                    break;
                }
                for sb in signs(b) {
                    for sa in signs(a) {
                        let d = [sa * a as i32, sb * b as i32];
                        let lin = d[0] as isize + cx as isize * d[1] as isize;
                        cells.push(Cell { lin, d, x, fy, lb });
                    }
                }
            }
        }
        cells.sort_by(|p, q| p.lb.total_cmp(&q.lb).then(p.lin.cmp(&q.lin)));
        // Whole groups: the padding lies outside every slab.
        let pad = Cell {
            lin: 0,
            d: [i32::MIN, i32::MIN],
            x: f64::INFINITY,
            fy: f64::INFINITY,
            lb: f64::INFINITY,
        };
        cells.resize(cells.len().next_multiple_of(GROUP), pad);
        Disc { cells, limit }
    }

    /// The offsets by ascending `lb`, in groups of [`GROUP`].
    #[inline]
    pub(super) fn groups(&self) -> std::slice::ChunksExact<'_, Cell> {
        self.cells.chunks_exact(GROUP)
    }
}

/// `[1]` for 0, `[1, -1]` otherwise.
fn signs(n: usize) -> &'static [i32] {
    if n == 0 { &[1] } else { &[1, -1] }
}
