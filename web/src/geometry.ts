/**
 * Small polygon helpers for display: where contours of slices along one
 * axis cut a line of an orthogonal view.
 */
import { axisDim, inPlane, type Axis, type Vec2 } from "./transform";

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

/**
 * Where the contours `polys` drawn on slice `index` along axis `work` cut the
 * plane of an orthogonal view along axis `view` at slice `viewIndex`: the
 * strips `[u0, v0, u1, v1]` in the view's slice coordinates. A strip is one
 * pixel thick across the working axis (`[index, index + 1)`) and spans the
 * inside intervals along the shared axis, sampled at the view slice's pixel
 * centre (`viewIndex + 0.5`), matching the pixel-centre rule.
 */
export function cutStrips(work: Axis, view: Axis, index: number, viewIndex: number, polys: Vec2[][]): [number, number, number, number][] {
  if (work === view) return [];
  const [au, av] = inPlane(work);
  const [bu] = inPlane(view);
  const db = axisDim(view);
  // The view fixes one of the working slice's in-plane dims; scan along the other.
  const swap = db === au;
  const along = swap ? av : au;
  const scan = swap ? polys.map((p) => p.map(([x, y]) => [y, x] as Vec2)) : polys;
  const out: [number, number, number, number][] = [];
  for (const [s0, s1] of scanlineIntervals(scan, viewIndex + 0.5)) {
    if (along === bu) out.push([s0, index, s1, index + 1]);
    else out.push([index, s0, index + 1, s1]);
  }
  return out;
}
