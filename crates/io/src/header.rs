//! Helpers shared by the text-header formats (NRRD, MetaImage): bounded
//! line reading and geometry assembly from per-axis vectors.
use crate::IoError;
use interslice_core::{Geometry, LengthUnit};
use std::io::BufRead;
use std::path::Path;

/// Longest text header we accept before deciding the file is not one.
pub const MAX_HEADER: usize = 1 << 20;

/// Read one line (without the line ending) of at most [`MAX_HEADER`] bytes;
/// `None` at end of file. `consumed` counts the bytes read, line ending included.
pub fn read_line<R: BufRead + ?Sized>(
    path: &Path,
    r: &mut R,
    consumed: &mut usize,
) -> Result<Option<String>, IoError> {
    let mut buf = Vec::new();
    let n = std::io::Read::take(&mut *r, (MAX_HEADER + 1) as u64)
        .read_until(b'\n', &mut buf)
        .map_err(|e| IoError::read(path, e))?;
    if n == 0 {
        return Ok(None);
    }
    *consumed += n;
    if *consumed > MAX_HEADER {
        return Err(IoError::invalid(
            path,
            "header is too long (is this a text header at all?)",
        ));
    }
    if buf.last() == Some(&b'\n') {
        buf.pop();
    }
    if buf.last() == Some(&b'\r') {
        buf.pop();
    }
    String::from_utf8(buf)
        .map(Some)
        .map_err(|_| IoError::invalid(path, "header is not text"))
}

/// Geometry from per-axis direction vectors whose lengths are the spacings
/// (NRRD `space directions`, or ITK direction columns × spacing).
pub fn geometry_from_axes(
    path: &Path,
    dims: [usize; 3],
    axes: [[f64; 3]; 3],
    origin: [f64; 3],
    unit: LengthUnit,
) -> Result<Geometry, IoError> {
    let mut spacing = [0.0; 3];
    let mut direction = [[0.0; 3]; 3];
    for c in 0..3 {
        let v = axes[c];
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if !(n.is_finite() && n > 0.0) {
            return Err(IoError::invalid(
                path,
                format!("axis {c} has a zero or invalid direction vector {v:?}"),
            ));
        }
        spacing[c] = snap(n);
        for r in 0..3 {
            direction[r][c] = v[r] / n + 0.0;
        }
    }
    let g = Geometry {
        dims,
        spacing,
        unit,
        origin,
        direction,
    };
    checked(path, g)
}

/// A geometry read from a header, checked: what [`Geometry::validate`]
/// checks (dims, spacing finite and positive, origin finite), and a
/// direction of finite, independent axes (degenerate `space directions` or
/// a `TransformMatrix` with two equal columns are an error).
pub fn checked(path: &Path, g: Geometry) -> Result<Geometry, IoError> {
    g.validate()
        .map_err(|e| IoError::invalid(path, e.to_string()))?;
    let d = g.direction;
    let det = d[0][0] * (d[1][1] * d[2][2] - d[1][2] * d[2][1])
        - d[0][1] * (d[1][0] * d[2][2] - d[1][2] * d[2][0])
        + d[0][2] * (d[1][0] * d[2][1] - d[1][1] * d[2][0]);
    let norms_ok = (0..3).all(|c| {
        let n = (0..3).map(|r| d[r][c] * d[r][c]).sum::<f64>().sqrt();
        (n - 1.0).abs() < 1e-3
    });
    if !(det.is_finite() && det.abs() > 1e-6 && norms_ok) {
        return Err(IoError::invalid(
            path,
            format!("direction {d:?} is degenerate (its axes must be independent unit vectors)"),
        ));
    }
    Ok(g)
}

/// A length computed as the norm of a vector (0.49999999999999994 from
/// `(0.25, 0.4330127018922193, 0)`) snapped to its 15-significant-digit
/// decimal when that is within 1e-15 relative: the value the file meant.
fn snap(x: f64) -> f64 {
    match format!("{x:.14e}").parse::<f64>() {
        Ok(d) if (d - x).abs() <= 1e-15 * x.abs() => d,
        _ => x,
    }
}

/// Format a float so it reads back exactly (Rust's shortest round-trip form).
pub fn num(x: f64) -> String {
    let x = x + 0.0; // no "-0"
    format!("{x}")
}
