import { describe, expect, it } from "vitest";
import { cutStrips, insidePolys, scanlineIntervals } from "../src/geometry";
import type { Vec2 } from "../src/transform";

describe("scanline intervals", () => {
  const square: Vec2[] = [
    [2, 2],
    [6, 2],
    [6, 6],
    [2, 6],
  ];
  it("cuts a square", () => {
    expect(scanlineIntervals([square], 3.5)).toEqual([[2, 6]]);
    expect(scanlineIntervals([square], 1.5)).toEqual([]);
    expect(scanlineIntervals([square], 6.5)).toEqual([]);
  });
  it("follows the even-odd rule for nested polygons", () => {
    const hole: Vec2[] = [
      [3, 3],
      [5, 3],
      [5, 5],
      [3, 5],
    ];
    expect(scanlineIntervals([square, hole], 4.5)).toEqual([
      [2, 3],
      [5, 6],
    ]);
    expect(insidePolys([square, hole], 4.5, 4.5)).toBe(false);
    expect(insidePolys([square, hole], 2.5, 4.5)).toBe(true);
  });
  it("counts pixel centres inside exactly like the pixel-centre rule", () => {
    // Triangle; count pixels whose centre is inside by brute force vs intervals.
    const tri: Vec2[] = [
      [0.3, 0.2],
      [9.7, 1.1],
      [4.2, 8.9],
    ];
    for (let b = 0; b < 10; b++) {
      const iv = scanlineIntervals([tri], b + 0.5);
      for (let a = 0; a < 10; a++) {
        const x = a + 0.5;
        const byIv = iv.some(([s, e]) => x >= s && x < e);
        expect(byIv).toBe(insidePolys([tri], x, b + 0.5));
      }
    }
  });
});

describe("cuts of working-axis contours in the orthogonal views", () => {
  // A square covering pixels i in [2,6), j in [3,8) on slice z = 10.
  const sq: Vec2[] = [
    [2, 3],
    [6, 3],
    [6, 8],
    [2, 8],
  ];
  // Brute force: voxel (i, j, k) is inside when its z slice is 10 and its centre is inside the square.
  const inside = (i: number, j: number, k: number) => k === 10 && insidePolys([sq], i + 0.5, j + 0.5);

  it("matches the voxels a y view and an x view see", () => {
    // y view at j = 4 shows (i, k): strips must cover exactly the inside voxels.
    const ys = cutStrips("z", "y", 10, 4, [sq]);
    expect(ys).toEqual([[2, 10, 6, 11]]);
    // x view at i = 3 shows (j, k).
    const xs = cutStrips("z", "x", 10, 3, [sq]);
    expect(xs).toEqual([[3, 10, 8, 11]]);
    for (const [view, at] of [["y", 4], ["x", 3], ["y", 7], ["x", 6]] as const) {
      const strips = cutStrips("z", view, 10, at, [sq]);
      for (let a = 0; a < 12; a++)
        for (let b = 0; b < 14; b++) {
          const covered = strips.some(([u0, v0, u1, v1]) => a + 0.5 >= u0 && a + 0.5 < u1 && b + 0.5 >= v0 && b + 0.5 < v1);
          const vox = view === "y" ? inside(a, at, b) : inside(at, a, b);
          expect(covered).toBe(vox);
        }
    }
  });

  it("works for every pair of axes", () => {
    // Contour on slice index 5 along `work`, a triangle in that slice's (u, v).
    const tri: Vec2[] = [
      [1.2, 0.7],
      [8.9, 2.1],
      [3.3, 9.4],
    ];
    const axes = ["x", "y", "z"] as const;
    const dimOf = { x: 0, y: 1, z: 2 };
    const plane = { x: [1, 2], y: [0, 2], z: [0, 1] };
    for (const work of axes)
      for (const view of axes) {
        if (work === view) continue;
        for (let at = 0; at < 10; at++) {
          const strips = cutStrips(work, view, 5, at, [tri]);
          for (let a = 0; a < 11; a++)
            for (let b = 0; b < 11; b++) {
              // The voxel of view pixel (a, b) on view slice `at`.
              const ijk = [0, 0, 0];
              ijk[dimOf[view]] = at;
              ijk[plane[view][0]] = a;
              ijk[plane[view][1]] = b;
              const inWork = ijk[dimOf[work]] === 5 && insidePolys([tri], ijk[plane[work][0]] + 0.5, ijk[plane[work][1]] + 0.5);
              const covered = strips.some(([u0, v0, u1, v1]) => a + 0.5 >= u0 && a + 0.5 < u1 && b + 0.5 >= v0 && b + 0.5 < v1);
              expect(covered).toBe(inWork);
            }
        }
      }
  });
});
