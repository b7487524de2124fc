import { describe, expect, it } from "vitest";
import { taubin } from "../src/smooth";

/** A UV sphere of radius `r` whose vertices are pushed in and out by `bump` (terraces). */
function bumpySphere(r: number, bump: number): { vertices: number[]; indices: number[] } {
  const rings = 24;
  const segs = 48;
  const vertices: number[] = [];
  const indices: number[] = [];
  for (let i = 0; i <= rings; i++) {
    const th = (Math.PI * i) / rings;
    for (let j = 0; j < segs; j++) {
      const ph = (2 * Math.PI * j) / segs;
      const rr = i === 0 || i === rings ? r : r + (i % 2 === 0 ? bump : -bump);
      vertices.push(rr * Math.sin(th) * Math.cos(ph), rr * Math.sin(th) * Math.sin(ph), rr * Math.cos(th));
    }
  }
  for (let i = 0; i < rings; i++)
    for (let j = 0; j < segs; j++) {
      const a = i * segs + j;
      const b = i * segs + ((j + 1) % segs);
      indices.push(a, a + segs, b, b, a + segs, b + segs);
    }
  return { vertices, indices };
}

function radii(v: ArrayLike<number>): number[] {
  const out: number[] = [];
  for (let p = 0; p < v.length; p += 3) out.push(Math.hypot(v[p], v[p + 1], v[p + 2]));
  return out;
}

const mean = (xs: number[]) => xs.reduce((a, b) => a + b, 0) / xs.length;
const spread = (xs: number[]) => Math.max(...xs) - Math.min(...xs);

describe("Taubin smoothing", () => {
  it("removes terraces without shrinking the surface", () => {
    const s = bumpySphere(10, 0.5);
    const out = taubin(s.vertices, s.indices);
    const before = radii(s.vertices);
    const after = radii(out);
    expect(spread(after)).toBeLessThan(spread(before) / 3);
    expect(Math.abs(mean(after) - 10)).toBeLessThan(0.3);
  });

  it("treats duplicated corners as one vertex", () => {
    // Two triangles of a square, each with its own copy of the shared edge.
    const v = [0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 0, 0, 1, 1, 0, 0, 1, 0];
    const out = taubin(v, [0, 1, 2, 3, 4, 5], 3);
    for (const [a, b] of [
      [0, 3],
      [2, 4],
    ])
      for (let d = 0; d < 3; d++) expect(out[3 * a + d]).toBeCloseTo(out[3 * b + d], 12);
  });

  it("keeps an empty mesh empty", () => {
    expect(taubin([], []).length).toBe(0);
  });
});
