/**
 * Small polygon helpers for display: where contours of slices along one
 * axis cut a line of an orthogonal view.
 */
import type { Vec2 } from "./transform";

/**
 * Even-odd crossings of the closed polygons `polys` with the line `v = y`:
 * sorted `[start, end)` intervals of u that are inside. Matches the
 * pixel-centre rule when `y` is a pixel centre (`b + 0.5`).
 */
export function scanlineIntervals(polys: Vec2[][], y: number): Vec2[] {
  const xs: number[] = [];
  for (const poly of polys) {
    const n = poly.length;
    for (let i = 0; i < n; i++) {
      const [x0, y0] = poly[i];
      const [x1, y1] = poly[(i + 1) % n];
      // Half-open rule: an edge counts when y is in [min, max), so vertices are not counted twice.
      if ((y0 <= y && y < y1) || (y1 <= y && y < y0)) {
        xs.push(x0 + ((y - y0) / (y1 - y0)) * (x1 - x0));
      }
    }
  }
  xs.sort((a, b) => a - b);
  const out: Vec2[] = [];
  for (let i = 0; i + 1 < xs.length; i += 2) if (xs[i + 1] > xs[i]) out.push([xs[i], xs[i + 1]]);
  return out;
}

/** Even-odd test: is `(x, y)` inside the union of `polys`? */
export function insidePolys(polys: Vec2[][], x: number, y: number): boolean {
  return scanlineIntervals(polys, y).some(([a, b]) => x >= a && x < b);
}
