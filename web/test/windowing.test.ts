import { describe, expect, it } from "vitest";
import { applyBrightnessContrast, autoWindow, buildLut, decodeSlice, grey, histogramQuantile, levelWidth, renderGrey, type Histogram } from "../src/windowing";

describe("window/level", () => {
  it("maps the window ends to black and white, linear between", () => {
    const w = { lo: 100, hi: 200 };
    expect(grey(50, w)).toBe(0);
    expect(grey(100, w)).toBe(0);
    expect(grey(150, w)).toBe(128); // 127.5 rounds up
    expect(grey(200, w)).toBe(255);
    expect(grey(60000, w)).toBe(255);
  });

  it("builds 8- and 16-bit lookup tables", () => {
    const w = { lo: 1000, hi: 3000 };
    const lut16 = buildLut("u16", w);
    expect(lut16.length).toBe(65536);
    expect(lut16[999]).toBe(0);
    expect(lut16[2000]).toBe(128);
    expect(lut16[3000]).toBe(255);
    const lut8 = buildLut("u8", { lo: 0, hi: 255 });
    for (let v = 0; v < 256; v++) expect(lut8[v]).toBe(v);
  });

  it("renders grey RGBA", () => {
    const out = new Uint8ClampedArray(8);
    renderGrey(new Uint8Array([0, 255]), buildLut("u8", { lo: 0, hi: 255 }), out);
    expect(Array.from(out)).toEqual([0, 0, 0, 255, 255, 255, 255, 255]);
  });

  it("decodes little-endian 16-bit slices", () => {
    const buf = new Uint8Array([0x34, 0x12, 0xff, 0xff, 0x00, 0x01]).buffer;
    expect(Array.from(decodeSlice(buf, "u16", 3, 1))).toEqual([0x1234, 0xffff, 0x0100]);
    expect(() => decodeSlice(buf, "u16", 4, 1)).toThrow();
    expect(Array.from(decodeSlice(buf, "u8", 2, 1))).toEqual([0x34, 0x12]);
  });

  it("histogram quantiles interpolate inside the bin", () => {
    // 4 bins of width 10 from 0: 10 voxels in [0,10), 30 in [20,30).
    const h: Histogram = { min: 0, max: 39, bin_width: 10, counts: [10, 0, 30, 0] };
    expect(histogramQuantile(h, 0)).toBe(0);
    expect(histogramQuantile(h, 0.125)).toBe(5);
    expect(histogramQuantile(h, 0.25)).toBe(10);
    expect(histogramQuantile(h, 0.625)).toBe(25);
    expect(histogramQuantile(h, 1)).toBe(30);
  });

  it("auto window ignores the extreme tails on 16-bit data", () => {
    // Background at 1000-1255, cell at 20000-20255, one hot voxel bin at 65000.
    const bw = 256;
    const counts = new Array(256).fill(0);
    counts[Math.floor(1000 / bw)] = 50000;
    counts[Math.floor(20000 / bw)] = 49000;
    counts[Math.floor(65000 / bw)] = 10;
    const h: Histogram = { min: 0, max: 65535, bin_width: bw, counts };
    const w = autoWindow(h);
    expect(w.lo).toBeGreaterThanOrEqual(768);
    expect(w.lo).toBeLessThan(1024);
    expect(w.hi).toBeGreaterThan(19968);
    expect(w.hi).toBeLessThanOrEqual(20224);
  });

  it("auto window of a flat volume is not empty", () => {
    const w = autoWindow({ min: 7, max: 7, bin_width: 1, counts: [100] });
    expect(w.hi).toBeGreaterThan(w.lo);
    expect(grey(7, w)).toBe(128);
  });

  it("brightness and contrast move the level and scale the width", () => {
    const base = { lo: 0, hi: 200 };
    expect(applyBrightnessContrast(base, 0, 0)).toEqual(base);
    const c = levelWidth(applyBrightnessContrast(base, 0, 25));
    expect(c).toEqual({ level: 100, width: 100 });
    const b = levelWidth(applyBrightnessContrast(base, 100, 0));
    expect(b).toEqual({ level: 0, width: 200 });
    // Brighter: a mid value gets a higher grey.
    expect(grey(100, applyBrightnessContrast(base, 50, 0))).toBeGreaterThan(grey(100, base));
  });
});
