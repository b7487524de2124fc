import { describe, expect, it } from "vitest";
import { insidePolys, scanlineIntervals } from "../src/geometry";
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
