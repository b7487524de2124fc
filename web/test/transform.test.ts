import { describe, expect, it } from "vitest";
import {
  canvasToSlice,
  fitTransform,
  panBy,
  pixelAt,
  sliceToCanvas,
  voxelOf,
  zoomAt,
  sliceShape,
  type ViewTransform,
} from "../src/transform";

// Deterministic pseudo-random numbers for property checks.
function rng(seed: number) {
  let s = seed >>> 0;
  return () => {
    s = (s * 1664525 + 1013904223) >>> 0;
    return s / 2 ** 32;
  };
}

describe("canvas <-> slice transform", () => {
  const t: ViewTransform = { scale: 4, aspect: 2, ox: 10, oy: -6 };

  it("maps pixel corners and centres exactly", () => {
    // Pixel (3, 5) covers canvas [22, 26) x [34, 42) at scale 4, aspect 2.
    expect(sliceToCanvas(t, 3, 5)).toEqual([22, 34]);
    expect(sliceToCanvas(t, 4, 6)).toEqual([26, 42]);
    expect(canvasToSlice(t, 24, 38)).toEqual([3.5, 5.5]);
    expect(pixelAt(...canvasToSlice(t, 22, 34), 10, 10)).toEqual([3, 5]);
    // The right/bottom edges belong to the next pixel.
    expect(pixelAt(...canvasToSlice(t, 26, 42), 10, 10)).toEqual([4, 6]);
    expect(pixelAt(...canvasToSlice(t, 25.999, 41.999), 10, 10)).toEqual([3, 5]);
  });

  it("pixelAt is null outside the slice", () => {
    expect(pixelAt(-0.001, 0, 4, 4)).toBeNull();
    expect(pixelAt(0, 4, 4, 4)).toBeNull();
    expect(pixelAt(3.999, 3.999, 4, 4)).toEqual([3, 3]);
  });

  it("round-trips for random transforms and points", () => {
    const r = rng(7);
    for (let n = 0; n < 2000; n++) {
      const tt: ViewTransform = {
        scale: 0.1 + r() * 50,
        aspect: 0.25 + r() * 4,
        ox: (r() - 0.5) * 1000,
        oy: (r() - 0.5) * 1000,
      };
      const u = (r() - 0.5) * 600;
      const v = (r() - 0.5) * 600;
      const [x, y] = sliceToCanvas(tt, u, v);
      const [u2, v2] = canvasToSlice(tt, x, y);
      expect(Math.abs(u2 - u)).toBeLessThan(1e-9);
      expect(Math.abs(v2 - v)).toBeLessThan(1e-9);
    }
  });

  it("zoom keeps the point under the cursor fixed", () => {
    const r = rng(11);
    for (let n = 0; n < 500; n++) {
      const tt: ViewTransform = { scale: 0.5 + r() * 10, aspect: 0.5 + r() * 2, ox: r() * 100, oy: r() * 100 };
      const x = r() * 800;
      const y = r() * 600;
      const before = canvasToSlice(tt, x, y);
      const z = zoomAt(tt, x, y, 0.3 + r() * 3);
      const after = canvasToSlice(z, x, y);
      expect(Math.abs(after[0] - before[0])).toBeLessThan(1e-9);
      expect(Math.abs(after[1] - before[1])).toBeLessThan(1e-9);
    }
  });

  it("zoom is clamped and pan shifts by the given canvas pixels", () => {
    const z = zoomAt(t, 0, 0, 1e9, 0.05, 200);
    expect(z.scale).toBe(200);
    const p = panBy(t, 5, -3);
    const [u, v] = canvasToSlice(t, 100, 100);
    expect(sliceToCanvas(p, u, v)).toEqual([105, 97]);
  });

  it("fit shows the whole slice centred with the aspect kept", () => {
    const f = fitTransform(100, 50, 2, 416, 216, 8);
    // Available 400 x 200; the slice is 100 x 100 physical: scale 2.
    expect(f.scale).toBe(2);
    expect(sliceToCanvas(f, 0, 0)).toEqual([108, 8]);
    expect(sliceToCanvas(f, 100, 50)).toEqual([308, 208]);
  });

  it("voxel and slice shapes follow DESIGN.md", () => {
    expect(voxelOf("z", 7, 1, 2)).toEqual([1, 2, 7]);
    expect(voxelOf("y", 7, 1, 2)).toEqual([1, 7, 2]);
    expect(voxelOf("x", 7, 1, 2)).toEqual([7, 1, 2]);
    expect(sliceShape("x", [10, 20, 30])).toEqual([20, 30, 10]);
    expect(sliceShape("y", [10, 20, 30])).toEqual([10, 30, 20]);
    expect(sliceShape("z", [10, 20, 30])).toEqual([10, 20, 30]);
  });
});
