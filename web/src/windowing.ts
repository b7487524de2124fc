/**
 * Window/level for 8- and 16-bit slices, applied in the browser.
 *
 * The server sends raw intensities; a window `[lo, hi]` maps `lo` and below
 * to black, `hi` and above to white and is linear in between. Brightness and
 * contrast are a friendlier parametrisation of the same window around an
 * automatic base window computed from the histogram.
 */

/** A display window in raw intensity units. */
export interface Window {
  /** Intensity shown black. */
  lo: number;
  /** Intensity shown white. */
  hi: number;
}

/** The server's histogram: `counts[b]` voxels in `[min + b*bin_width, min + (b+1)*bin_width)`. */
export interface Histogram {
  /** Lowest intensity. */
  min: number;
  /** Highest intensity. */
  max: number;
  /** Width of one bin in intensity units. */
  bin_width: number;
  /** Voxel count per bin. */
  counts: number[];
}

/** Window centre and width ("level" and "window" in radiology terms). */
export function levelWidth(w: Window): { level: number; width: number } {
  return { level: (w.lo + w.hi) / 2, width: w.hi - w.lo };
}

/** The window of a level (centre) and width. */
export function fromLevelWidth(level: number, width: number): Window {
  const wd = Math.max(1e-6, width);
  return { lo: level - wd / 2, hi: level + wd / 2 };
}

/**
 * The intensity below which a fraction `q` (0..1) of the voxels lie,
 * interpolating linearly inside the bin where the cumulative count crosses.
 */
export function histogramQuantile(h: Histogram, q: number): number {
  const total = h.counts.reduce((a, b) => a + b, 0);
  if (total === 0) return h.min;
  const target = Math.min(1, Math.max(0, q)) * total;
  let cum = 0;
  for (let b = 0; b < h.counts.length; b++) {
    const c = h.counts[b];
    if (c > 0 && cum + c >= target) {
      const frac = (target - cum) / c;
      return Math.min(h.max, h.min + (b + frac) * h.bin_width);
    }
    cum += c;
  }
  return h.max;
}

/**
 * The automatic window: from the `lowFrac` to the `highFrac` quantile of
 * the histogram (0.5 % and 99.5 % by default, which ignores a few hot or
 * dead voxels). Falls back to the full range when the volume is flat.
 */
export function autoWindow(h: Histogram, lowFrac = 0.005, highFrac = 0.995): Window {
  const lo = histogramQuantile(h, lowFrac);
  const hi = histogramQuantile(h, highFrac);
  if (hi - lo < 1e-9) {
    return h.max > h.min ? { lo: h.min, hi: h.max } : { lo: h.min - 0.5, hi: h.min + 0.5 };
  }
  return { lo, hi };
}

/**
 * Brightness and contrast (each -100..100, 0 = base) applied to a base
 * window. Contrast +25 halves the width; brightness +100 moves the level
 * down by half the base width (the picture gets brighter).
 */
export function applyBrightnessContrast(base: Window, brightness: number, contrast: number): Window {
  const { level, width } = levelWidth(base);
  const w = width * Math.pow(2, -contrast / 25);
  const l = level - (brightness / 100) * (width / 2);
  return fromLevelWidth(l, w);
}

/** Grey level 0..255 of `value` under window `w`. */
export function grey(value: number, w: Window): number {
  if (value <= w.lo) return 0;
  if (value >= w.hi) return 255;
  return Math.round(((value - w.lo) / (w.hi - w.lo)) * 255);
}

/** A lookup table from raw value to grey, 256 entries for u8 and 65536 for u16. */
export function buildLut(dtype: "u8" | "u16", w: Window): Uint8Array {
  const n = dtype === "u8" ? 256 : 65536;
  const lut = new Uint8Array(n);
  for (let v = 0; v < n; v++) lut[v] = grey(v, w);
  return lut;
}

/** Fill RGBA `out` (4 bytes per pixel, opaque) from raw pixels through `lut`. */
export function renderGrey(raw: Uint8Array | Uint16Array, lut: Uint8Array, out: Uint8ClampedArray): void {
  const n = raw.length;
  for (let p = 0, o = 0; p < n; p++, o += 4) {
    const g = lut[raw[p]];
    out[o] = g;
    out[o + 1] = g;
    out[o + 2] = g;
    out[o + 3] = 255;
  }
}

/**
 * Decode a raw little-endian slice (the server's octet-stream) into a typed
 * array, independent of the host's byte order.
 */
export function decodeSlice(buf: ArrayBuffer, dtype: "u8" | "u16", width: number, height: number): Uint8Array | Uint16Array {
  const n = width * height;
  if (dtype === "u8") {
    if (buf.byteLength < n) throw new Error(`slice has ${buf.byteLength} bytes, expected ${n}`);
    return new Uint8Array(buf, 0, n);
  }
  if (buf.byteLength < 2 * n) throw new Error(`slice has ${buf.byteLength} bytes, expected ${2 * n}`);
  const dv = new DataView(buf);
  const out = new Uint16Array(n);
  for (let p = 0; p < n; p++) out[p] = dv.getUint16(2 * p, true);
  return out;
}
