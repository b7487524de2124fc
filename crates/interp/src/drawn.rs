//! Which slices were drawn: every slice with a non-zero voxel along the axis,
//! or the indices listed in a `--drawn` file (which can also declare slices
//! that were drawn empty).
use crate::InterpError;
use interslice_core::{Axis, LabelVolume};
use rayon::prelude::*;

/// Indices of the slices along `axis` that hold any non-zero voxel, ascending.
pub fn nonempty_slices(volume: &LabelVolume, axis: Axis) -> Vec<usize> {
    let n = volume.slice_count(axis);
    let [nx, ny, _] = volume.dims();
    let data = volume.data();
    let mut hit = vec![false; n];
    match axis {
        Axis::Z => {
            hit = data
                .par_chunks(nx * ny)
                .map(|p| p.iter().any(|&v| v != 0))
                .collect();
        }
        Axis::Y | Axis::X => {
            // One pass over z-planes in parallel, OR-ed per slice index.
            let per_plane: Vec<Vec<bool>> = data
                .par_chunks(nx * ny)
                .map(|p| {
                    let mut h = vec![false; n];
                    for j in 0..ny {
                        for i in 0..nx {
                            if p[i + nx * j] != 0 {
                                h[if axis == Axis::X { i } else { j }] = true;
                            }
                        }
                    }
                    h
                })
                .collect();
            for h in per_plane {
                for (a, b) in hit.iter_mut().zip(h) {
                    *a |= b;
                }
            }
        }
    }
    (0..n).filter(|&s| hit[s]).collect()
}

/// Parse a `--drawn` file: one slice index a line; blank lines and `#`
/// comments (whole-line or trailing) are ignored. `count` is the number of
/// slices along the axis. The result is sorted and de-duplicated.
///
/// Errors name the 1-based line of the first non-numeric or out-of-range entry.
pub fn parse_drawn(text: &str, count: usize) -> Result<Vec<usize>, InterpError> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let content = line.split('#').next().unwrap_or("").trim();
        if content.is_empty() {
            continue;
        }
        let idx: usize = content.parse().map_err(|_| {
            InterpError::Input(format!(
                "drawn list line {}: '{content}' is not a slice index (a non-negative integer)",
                i + 1
            ))
        })?;
        if idx >= count {
            return Err(InterpError::Input(format!(
                "drawn list line {}: slice {idx} is out of range (0..{count})",
                i + 1
            )));
        }
        out.push(idx);
    }
    out.sort_unstable();
    out.dedup();
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use interslice_core::{Geometry, LengthUnit, Volume};

    #[test]
    fn parses_comments_blank_lines_and_duplicates() {
        let got = parse_drawn("# header\n4\n\n 0 \n9 # last\n4\n", 10).unwrap();
        assert_eq!(got, vec![0, 4, 9]);
    }

    #[test]
    fn errors_name_the_line() {
        let e = parse_drawn("1\n2\nthree\n", 10).unwrap_err().to_string();
        assert!(e.contains("line 3") && e.contains("three"), "{e}");
        let e = parse_drawn("1\n\n10\n", 10).unwrap_err().to_string();
        assert!(e.contains("line 3") && e.contains("out of range"), "{e}");
        let e = parse_drawn("-1\n", 10).unwrap_err().to_string();
        assert!(e.contains("line 1"), "{e}");
    }

    #[test]
    fn nonempty_slices_on_every_axis() {
        let g = Geometry::new([4, 5, 6], [1.0, 1.0, 2.0], LengthUnit::Micrometre).unwrap();
        let mut v: LabelVolume = Volume::zeros(g);
        v.set(1, 2, 3, 7);
        v.set(3, 4, 5, 1);
        assert_eq!(nonempty_slices(&v, Axis::X), vec![1, 3]);
        assert_eq!(nonempty_slices(&v, Axis::Y), vec![2, 4]);
        assert_eq!(nonempty_slices(&v, Axis::Z), vec![3, 5]);
    }
}
