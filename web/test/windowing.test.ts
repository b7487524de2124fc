import { describe, expect, it } from "vitest";
import {
  AUTO_PRESET,
  CT_PRESETS,
  DTYPES,
  applyBrightnessContrast,
  autoWindow,
  buildLut,
  bytesPerVoxel,
  decodeSlice,
  defaultPreset,
  formatValue,
  grey,
  histogramCdf,
  histogramQuantile,
  levelWidth,
  looksLikeCT,
  parseDtype,
  presetWindow,
  presetsFor,
  renderGrey,
  windowText,
  type Dtype,
  type Histogram,
  type RawPixels,
} from "../src/windowing";

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
    expect(lut16.table!.length).toBe(65536);
    expect(lut16.table![999]).toBe(0);
    expect(lut16.table![2000]).toBe(128);
    expect(lut16.table![3000]).toBe(255);
    const lut8 = buildLut("u8", { lo: 0, hi: 255 });
    for (let v = 0; v < 256; v++) expect(lut8.table![v]).toBe(v);
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
    expect(Array.from(decodeSlice(buf.slice(0, 2), "u8", 2, 1))).toEqual([0x34, 0x12]);
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
    const counts = new Array<number>(256).fill(0);
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

/** Little-endian bytes of values of a voxel type, written byte by byte (independent of the host's order). */
function leBytes(dtype: Dtype, values: number[]): ArrayBuffer {
  const n = bytesPerVoxel(dtype);
  const dv = new DataView(new ArrayBuffer(values.length * n));
  values.forEach((v, i) => {
    if (dtype === "u8") dv.setUint8(i, v);
    else if (dtype === "u16") dv.setUint16(2 * i, v, true);
    else if (dtype === "i16") dv.setInt16(2 * i, v, true);
    else dv.setFloat32(4 * i, v, true);
  });
  return dv.buffer;
}

describe("binary slices of every voxel type", () => {
  // What the readers produce: u8; u16 (also u32 files whose values fit);
  // i16 (also i8 files, and i32 files whose values fit); f32 (also f64
  // files exact in f32, and any NIfTI with scl_slope/scl_inter applied).
  const samples: Record<Dtype, number[]> = {
    u8: [0, 1, 127, 128, 255, 7],
    u16: [0, 1, 255, 256, 32768, 65535],
    i16: [-32768, -1024, -1000, -1, 0, 32767],
    f32: [-1000, -0.5, 0, 0.1, 3.4028234663852886e38, Number.NaN],
  };

  it("decodes each voxel type to its values, row-major", () => {
    for (const d of DTYPES) {
      const vals = samples[d];
      const raw = decodeSlice(leBytes(d, vals), d, 3, 2);
      expect(raw.length).toBe(6);
      const want = d === "f32" ? vals.map((v) => Math.fround(v)) : vals;
      expect(Array.from(raw)).toEqual(want);
    }
  });

  it("reads the bytes in little-endian order", () => {
    expect(Array.from(decodeSlice(new Uint8Array([0x18, 0xfc]).buffer, "i16", 1, 1))).toEqual([-1000]);
    expect(Array.from(decodeSlice(new Uint8Array([0x00, 0x00, 0x7a, 0xc4]).buffer, "f32", 1, 1))).toEqual([-1000]);
  });

  it("refuses a body whose size does not match the type and shape", () => {
    // A 2x1 f32 slice read as u16 (the old bug showed stripes): refused.
    const f = leBytes("f32", [1.5, -2]);
    expect(() => decodeSlice(f, "u16", 2, 1)).toThrow(/u16 slice of 2x1 has 8 bytes, expected 4/);
    expect(() => decodeSlice(f, "f32", 3, 1)).toThrow();
    expect(() => decodeSlice(leBytes("i16", [1, 2, 3]), "i16", 1, 1)).toThrow();
  });

  it("names the voxel type of the X-Dtype header, and refuses others", () => {
    for (const d of DTYPES) expect(parseDtype(d)).toBe(d);
    expect(parseDtype("I16")).toBe("i16");
    for (const bad of [null, "", "f64", "i32", "u16 "]) {
      if (bad === "u16 ") expect(parseDtype(bad)).toBe("u16");
      else expect(() => parseDtype(bad)).toThrow(/unsupported slice voxel type/);
    }
  });

  it("windows every value of every type as grey() does", () => {
    const w = { lo: -160.5, hi: 240.25 };
    for (const d of DTYPES) {
      const lut = buildLut(d, w);
      const vals =
        d === "f32"
          ? [-1e30, -160.5, -160.4, 0, 39.9, 240.2, 240.25, 1e30, -Infinity, Infinity]
          : samples[d]
              .concat([-160, 40, 240, 241])
              .filter((v) => (d === "i16" ? true : v >= 0) && (d === "u8" ? v <= 255 : true));
      const raw: RawPixels =
        d === "u8"
          ? Uint8Array.from(vals)
          : d === "u16"
            ? Uint16Array.from(vals)
            : d === "i16"
              ? Int16Array.from(vals)
              : Float32Array.from(vals);
      const out = new Uint8ClampedArray(4 * raw.length);
      renderGrey(raw, lut, out);
      raw.forEach((v, p) => {
        expect(out[4 * p], `${d} ${v}`).toBe(grey(v, w));
        expect(out[4 * p + 1]).toBe(out[4 * p]);
        expect(out[4 * p + 3]).toBe(255);
      });
    }
  });

  it("the i16 table covers -32768..32767 (air dark in a soft-tissue window)", () => {
    const w = { lo: -160, hi: 240 };
    const lut = buildLut("i16", w);
    expect(lut.table!.length).toBe(65536);
    for (let v = -32768; v <= 32767; v += 97) expect(lut.table![v - lut.offset]).toBe(grey(v, w));
    const out = new Uint8ClampedArray(12);
    renderGrey(Int16Array.from([-1000, 40, 1000]), lut, out);
    expect([out[0], out[4], out[8]]).toEqual([0, 128, 255]);
  });

  it("NaN is black and infinities clamp in f32 slices", () => {
    const out = new Uint8ClampedArray(12);
    renderGrey(Float32Array.from([Number.NaN, -Infinity, Infinity]), buildLut("f32", { lo: 0, hi: 1 }), out);
    expect([out[0], out[4], out[8]]).toEqual([0, 0, 255]);
  });

  it("shows the raw value in the file's units", () => {
    expect(formatValue(-1000, "i16")).toBe("-1000");
    expect(formatValue(65535, "u16")).toBe("65535");
    expect(formatValue(Math.fround(0.1), "f32")).toBe("0.1");
    expect(formatValue(Math.fround(-1234.5678), "f32")).toBe("-1234.57");
    expect(formatValue(Math.fround(1.5e-7), "f32")).toBe("1.5e-7");
    expect(formatValue(0, "f32")).toBe("0");
    expect(formatValue(Number.NaN, "f32")).toBe("NaN");
    expect(windowText(-1350.4, "i16")).toBe("-1350");
    expect(windowText(0.012345, "f32")).toBe("0.01235");
    expect(windowText(2048.6, "f32")).toBe("2049");
  });
});

/** A histogram of 256 bins from `min` with `count` voxels at each of `at` (value → count). */
function hist(min: number, max: number, at: [number, number][]): Histogram {
  const bin_width = Math.ceil((max - min + 1) / 256);
  const counts = new Array<number>(256).fill(0);
  for (const [v, n] of at) counts[Math.min(255, Math.floor((v - min) / bin_width))] += n;
  return { min, max, bin_width, counts };
}

describe("window presets", () => {
  // A chest CT: air around the body, lung, soft tissue, bone.
  const chest = hist(-1024, 3071, [
    [-1000, 40000],
    [-850, 15000],
    [40, 35000],
    [700, 10000],
  ]);
  // A head CT with the scanner's -3024 padding outside the field of view, no lung.
  const head = hist(-3024, 3071, [
    [-3024, 20000],
    [-1000, 10000],
    [30, 50000],
    [1000, 20000],
  ]);
  // An MR: non-negative, no air at -1000.
  const mr = hist(0, 1800, [
    [0, 30000],
    [400, 50000],
    [900, 20000],
  ]);

  it("the CT windows in Hounsfield units", () => {
    const w = (id: string) =>
      presetWindow(
        CT_PRESETS.find((p) => p.id === id)!,
        chest,
        chest,
      );
    expect(w("ct-lung")).toEqual({ lo: -1350, hi: 150 });
    expect(w("ct-soft-tissue")).toEqual({ lo: -160, hi: 240 });
    expect(w("ct-bone")).toEqual({ lo: -500, hi: 1300 });
    expect(w("ct-brain")).toEqual({ lo: 0, hi: 80 });
    // In the lung window air is black, lung grey, soft tissue near white.
    const lung = w("ct-lung");
    expect(grey(-1000, lung)).toBeLessThan(70);
    expect(grey(-850, lung)).toBeGreaterThan(70);
    expect(grey(-850, lung)).toBeLessThan(110);
    expect(grey(40, lung)).toBeGreaterThan(225);
  });

  it("CT is recognised from its histogram, signed or float, not MR", () => {
    expect(looksLikeCT(chest, "i16")).toBe(true);
    expect(looksLikeCT(chest, "f32")).toBe(true); // rescaled NIfTI
    expect(looksLikeCT(head, "i16")).toBe(true);
    expect(looksLikeCT(mr, "i16")).toBe(false);
    expect(looksLikeCT(mr, "u16")).toBe(false);
    // Unsigned data never holds Hounsfield units.
    expect(looksLikeCT(chest, "u16")).toBe(false);
    // A few negative voxels (an MR after filtering) are not air.
    expect(
      looksLikeCT(
        hist(-950, 1800, [
          [-950, 10],
          [400, 100000],
        ]),
        "f32",
      ),
    ).toBe(false);
  });

  it("offers the CT windows for CT only; opens chest CT in the lung window, other CT in soft tissue, the rest automatic", () => {
    expect(presetsFor(chest, "i16").map((p) => p.id)).toEqual([
      "auto",
      "ct-soft-tissue",
      "ct-lung",
      "ct-bone",
      "ct-brain",
    ]);
    expect(presetsFor(mr, "i16")).toEqual([AUTO_PRESET]);
    expect(presetsFor(null, "i16")).toEqual([AUTO_PRESET]);
    expect(defaultPreset(chest, "i16").id).toBe("ct-lung");
    expect(defaultPreset(head, "i16").id).toBe("ct-soft-tissue");
    expect(defaultPreset(mr, "i16").id).toBe("auto");
    expect(defaultPreset(null, "f32").id).toBe("auto");
  });

  it("the automatic preset is the percentile window; without a histogram the cell's range", () => {
    expect(presetWindow(AUTO_PRESET, mr, mr)).toEqual(autoWindow(mr));
    expect(presetWindow(AUTO_PRESET, null, { min: -5, max: 5 })).toEqual({ lo: -5, hi: 5 });
    expect(presetWindow(AUTO_PRESET, null, { min: 3, max: 3 })).toEqual({ lo: 3, hi: 4 });
  });

  it("the cumulative fraction interpolates inside a bin", () => {
    const h: Histogram = { min: 0, max: 39, bin_width: 10, counts: [10, 0, 30, 0] };
    expect(histogramCdf(h, -5)).toBe(0);
    expect(histogramCdf(h, 5)).toBe(0.125);
    expect(histogramCdf(h, 20)).toBe(0.25);
    expect(histogramCdf(h, 25)).toBe(0.625);
    expect(histogramCdf(h, 100)).toBe(1);
    // The inverse of the quantile.
    for (const q of [0.1, 0.3, 0.5, 0.9]) expect(histogramCdf(h, histogramQuantile(h, q))).toBeCloseTo(q, 9);
  });
});
