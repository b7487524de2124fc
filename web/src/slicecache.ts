/**
 * The decoded slices of one cell, least recently used first out, each with
 * its windowed grey picture. A slice asked for twice while loading is
 * fetched once; a picture made with an older window is redrawn when asked
 * for, so changing the window never refetches.
 */
import type { RawSlice } from "./api";
import type { SliceImage } from "./sliceview";
import type { Axis } from "./transform";
import { buildLut, decodeSlice, renderGrey, type Dtype, type Lut, type Window } from "./windowing";

/** Slices kept (about 40 MB of 256² u16 slices with their pictures). */
const CAPACITY = 160;

/** The slice cache of one cell. */
export class SliceCache {
  private cache = new Map<string, SliceImage>();
  private inflight = new Map<string, Promise<SliceImage>>();
  private lut: Lut = buildLut("u8", { lo: 0, hi: 255 });
  private lutVersion = 0;

  constructor(
    /** Fetches a raw slice. */
    private fetchSlice: (axis: Axis, index: number) => Promise<RawSlice>,
    /** The volume's voxel type. */
    private dtype: Dtype,
    private capacity = CAPACITY,
  ) {}

  /** Use a new display window (pictures are redrawn as they are shown). */
  setWindow(win: Window): void {
    this.lut = buildLut(this.dtype, win);
    this.lutVersion++;
  }

  /** Redraw a slice's picture if it was made with an older window. */
  refresh(img: SliceImage): void {
    if (img.lutVersion !== this.lutVersion) this.repaint(img);
  }

  /** The slice `index` along `axis`, from the cache or the server. */
  get(axis: Axis, index: number): Promise<SliceImage> {
    const key = `${axis}/${index}`;
    const hit = this.cache.get(key);
    if (hit) {
      this.cache.delete(key);
      this.cache.set(key, hit); // LRU order
      this.refresh(hit);
      return Promise.resolve(hit);
    }
    let p = this.inflight.get(key);
    if (!p) {
      p = this.fetchSlice(axis, index).then((r) => {
        const raw = decodeSlice(r.data, r.dtype, r.width, r.height);
        const bitmap = document.createElement("canvas");
        bitmap.width = r.width;
        bitmap.height = r.height;
        const img: SliceImage = { width: r.width, height: r.height, raw, bitmap, lutVersion: -1 };
        this.repaint(img);
        this.cache.set(key, img);
        while (this.cache.size > this.capacity) this.cache.delete(this.cache.keys().next().value as string);
        return img;
      });
      this.inflight.set(key, p);
      p.finally(() => this.inflight.delete(key)).catch(() => {});
    }
    return p;
  }

  private repaint(img: SliceImage): void {
    const ctx = img.bitmap.getContext("2d");
    if (!ctx) return;
    const data = ctx.createImageData(img.width, img.height);
    renderGrey(img.raw, this.lut, data.data);
    ctx.putImageData(data, 0, 0);
    img.lutVersion = this.lutVersion;
  }
}
