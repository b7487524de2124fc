/**
 * Slice decoding and window/level, applied in the browser.
 *
 * The server sends raw intensities in the voxel type of the volume (`u8`,
 * `u16`, `i16` or `f32`, docs/API.md "Binary slices"); a window `[lo, hi]`
 * maps `lo` and below to black, `hi` and above to white and is linear in
 * between. Brightness and contrast are a friendlier parametrisation of the
 * same window around a base window: a preset (CT) or the automatic window
 * computed from the histogram.
 */

/** Voxel types of the binary slices (the `X-Dtype` header). */
export type Dtype = "u8" | "u16" | "i16" | "f32";

/** Every voxel type the server sends. */
export const DTYPES: readonly Dtype[] = ["u8", "u16", "i16", "f32"];

/** Raw intensities of a decoded slice, one typed array per voxel type. */
export type RawPixels = Uint8Array | Uint16Array | Int16Array | Float32Array;

/** Bytes per voxel of a type. */
export function bytesPerVoxel(d: Dtype): number {
  return d === "u8" ? 1 : d === "f32" ? 4 : 2;
}

/** The voxel type named by an `X-Dtype` header; anything else is an error (never guessed). */
export function parseDtype(s: string | null): Dtype {
  const d = (s ?? "").trim().toLowerCase();
  if ((DTYPES as readonly string[]).includes(d)) return d as Dtype;
  throw new Error(`unsupported slice voxel type '${s ?? ""}' (expected ${DTYPES.join(", ")})`);
}

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
  // `!(value > lo)` is also true for NaN: black.
  if (!(value > w.lo)) return 0;
  if (value >= w.hi) return 255;
  return Math.round(((value - w.lo) / (w.hi - w.lo)) * 255);
}

/**
 * The grey levels of a window for one voxel type: a table over every value
 * of an integer type (256 entries for u8, 65536 for u16 and i16, indexed by
 * `value - offset`), or the window itself for f32, whose values are mapped
 * one by one.
 */
export interface Lut {
  /** Grey of `value` at `table[value - offset]`; null for floats. */
  table: Uint8Array | null;
  /** Smallest value of the type (0, or -32768 for i16). */
  offset: number;
  /** The window the table was made from. */
  window: Window;
}

/** The lookup table of window `w` for voxel type `dtype`. */
export function buildLut(dtype: Dtype, w: Window): Lut {
  if (dtype === "f32") return { table: null, offset: 0, window: w };
  const offset = dtype === "i16" ? -32768 : 0;
  const n = dtype === "u8" ? 256 : 65536;
  const table = new Uint8Array(n);
  for (let i = 0; i < n; i++) table[i] = grey(i + offset, w);
  return { table, offset, window: w };
}

/**
 * Fill RGBA `out` (4 bytes per pixel, opaque) from raw pixels through `lut`.
 * Float values outside the window clamp to black or white; NaN is black.
 */
export function renderGrey(raw: RawPixels, lut: Lut, out: Uint8ClampedArray): void {
  const n = raw.length;
  const { table, offset } = lut;
  if (table) {
    for (let p = 0, o = 0; p < n; p++, o += 4) {
      const g = table[raw[p] - offset];
      out[o] = g;
      out[o + 1] = g;
      out[o + 2] = g;
      out[o + 3] = 255;
    }
    return;
  }
  const w = lut.window;
  for (let p = 0, o = 0; p < n; p++, o += 4) {
    const g = grey(raw[p], w);
    out[o] = g;
    out[o + 1] = g;
    out[o + 2] = g;
    out[o + 3] = 255;
  }
}

/**
 * Decode a raw little-endian slice (the server's octet-stream) into the
 * typed array of its voxel type, independent of the host's byte order. The
 * length must be exactly `width * height` voxels: a body of another size
 * means the type or shape was misread, and is refused rather than shown.
 */
export function decodeSlice(buf: ArrayBuffer, dtype: Dtype, width: number, height: number): RawPixels {
  const n = width * height;
  const need = n * bytesPerVoxel(dtype);
  if (buf.byteLength !== need)
    throw new Error(`${dtype} slice of ${width}x${height} has ${buf.byteLength} bytes, expected ${need}`);
  if (dtype === "u8") return new Uint8Array(buf, 0, n);
  const dv = new DataView(buf);
  if (dtype === "u16") {
    const out = new Uint16Array(n);
    for (let p = 0; p < n; p++) out[p] = dv.getUint16(2 * p, true);
    return out;
  }
  if (dtype === "i16") {
    const out = new Int16Array(n);
    for (let p = 0; p < n; p++) out[p] = dv.getInt16(2 * p, true);
    return out;
  }
  const out = new Float32Array(n);
  for (let p = 0; p < n; p++) out[p] = dv.getFloat32(4 * p, true);
  return out;
}

/**
 * A raw value as the status line shows it, in the file's units: integers as
 * they are, floats with up to 6 significant digits (what an f32 holds).
 */
export function formatValue(v: number, dtype: Dtype): string {
  if (dtype !== "f32" || !Number.isFinite(v)) return String(v);
  if (v === 0) return "0";
  return String(Number(v.toPrecision(6)));
}

/** A named base window: a fixed level/width, or the automatic window. */
export interface Preset {
  /** Stable id (kept in the view settings). */
  id: string;
  /** Shown in the preset menu. */
  name: string;
  /** Centre in raw units (absent for the automatic window). */
  level?: number;
  /** Width in raw units (absent for the automatic window). */
  width?: number;
}

/** The automatic window (0.5 % to 99.5 % of the histogram). */
export const AUTO_PRESET: Preset = { id: "auto", name: "Auto (percentiles)" };

/**
 * The usual CT windows in Hounsfield units (level/width): soft tissue
 * 40/400, lung -600/1500, bone 400/1800, brain 40/80.
 */
export const CT_PRESETS: readonly Preset[] = [
  { id: "ct-soft-tissue", name: "CT soft tissue", level: 40, width: 400 },
  { id: "ct-lung", name: "CT lung", level: -600, width: 1500 },
  { id: "ct-bone", name: "CT bone", level: 400, width: 1800 },
  { id: "ct-brain", name: "CT brain", level: 40, width: 80 },
];

/** The fraction (0..1) of voxels below `x`, interpolating linearly inside a bin. */
export function histogramCdf(h: Histogram, x: number): number {
  const total = h.counts.reduce((a, b) => a + b, 0);
  if (total === 0 || h.bin_width <= 0) return 0;
  const pos = (x - h.min) / h.bin_width;
  let below = 0;
  for (let b = 0; b < h.counts.length; b++) {
    if (pos >= b + 1) below += h.counts[b];
    else {
      if (pos > b) below += h.counts[b] * (pos - b);
      break;
    }
  }
  return Math.min(1, below / total);
}

/**
 * Whether a volume looks like CT in Hounsfield units: a signed or float
 * type, air (about -1000, or the -1024..-3024 padding of scanners) as the
 * lowest values, at least 1 % of the voxels at or below -900 and something
 * denser than water. Neither NIfTI nor NRRD record the modality, so the
 * histogram decides; the preset menu offers the CT windows only then.
 */
export function looksLikeCT(h: Histogram, dtype: Dtype): boolean {
  if (dtype !== "i16" && dtype !== "f32") return false;
  if (!(h.min <= -900 && h.min >= -3100 && h.max >= 100)) return false;
  return histogramCdf(h, -900) >= 0.01;
}

/** The presets offered for a volume: the automatic window, then the CT windows for CT. */
export function presetsFor(h: Histogram | null, dtype: Dtype): Preset[] {
  return h && looksLikeCT(h, dtype) ? [AUTO_PRESET, ...CT_PRESETS] : [AUTO_PRESET];
}

/**
 * The preset a volume opens with: for CT the lung window when at least 5 %
 * of the voxels are lung parenchyma (-950..-500 HU), the soft-tissue window
 * otherwise; the automatic window for everything else.
 */
export function defaultPreset(h: Histogram | null, dtype: Dtype): Preset {
  if (!h || !looksLikeCT(h, dtype)) return AUTO_PRESET;
  const lung = histogramCdf(h, -500) - histogramCdf(h, -950);
  return CT_PRESETS.find((p) => p.id === (lung >= 0.05 ? "ct-lung" : "ct-soft-tissue"))!;
}

/** The base window of a preset (the automatic one from the histogram, or the cell's range without one). */
export function presetWindow(p: Preset, h: Histogram | null, range: { min: number; max: number }): Window {
  if (p.level !== undefined && p.width !== undefined) return fromLevelWidth(p.level, p.width);
  if (h) return autoWindow(h);
  return { lo: range.min, hi: range.max > range.min ? range.max : range.min + 1 };
}

/**
 * A window end as the window fields show it: whole numbers for integer
 * types, 4 significant digits for floats (whose range may be 0..1).
 */
export function windowText(x: number, dtype: Dtype): string {
  if (dtype !== "f32") return String(Math.round(x));
  return x === 0 ? "0" : String(Number(x.toPrecision(4)));
}
