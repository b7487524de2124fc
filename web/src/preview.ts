/**
 * The live interpolation preview: after each change the label being traced
 * is interpolated along the working axis and shown dashed on the skipped
 * slices. One request runs at a time; changes made meanwhile ask for one
 * more run when it ends, so the preview catches up without piling requests.
 */
import type { Api, InterpResult } from "./api";
import type { Axis } from "./transform";

/**
 * The method exports use when none is picked ("recommended"). Per label, the
 * image-guided method is what the recommendation picks: where its
 * leave-one-out finds the image unhelpful it is the shape default, bit for
 * bit. So an export with it gives every label the result its preview showed.
 */
export const RECOMMENDED_FOR_EXPORT = "image-guided";

/** The method of an export: the one picked, else the recommended one per label. */
export function exportMethod(picked: string): string {
  return picked || RECOMMENDED_FOR_EXPORT;
}

/** What is interpolated: the label being traced, its axis, the chosen method ("" = recommended). */
export interface PreviewTarget {
  label: number;
  axis: Axis;
  method: string;
  /** Ask for the uncertain outlines of the skipped slices ("Show uncertainty"). */
  confidence: boolean;
}

/**
 * The words beside the method menu: which method the preview used and why.
 * With no method picked (`picked` empty) the server ran the one leave-one-out
 * recommends and said so; with one picked there is nothing to explain.
 */
export function methodNote(r: InterpResult | undefined, picked: string): string {
  if (picked || !r?.recommended_method) return "";
  const rec = r.recommended_method;
  const drawn = r.slices.filter((s) => s.drawn).length;
  // The server recommends the image-guided method exactly where it reads
  // the image (its fusion, `image_weight` > 0, or its walk, weight 0). With
  // two drawn slices nothing is held out: it walks where the outlines lie
  // on a clear intensity edge.
  if (rec === RECOMMENDED_FOR_EXPORT && drawn < 3) return `${rec}: your outlines follow a clear edge in the image`;
  if (rec === RECOMMENDED_FOR_EXPORT) return `${rec}: the image predicts your drawn slices better`;
  if (drawn < 3) return `${rec}: a third drawn slice lets the image be tested`;
  return `${rec}: the image did not help`;
}

/** What the screen does around a preview run. */
export interface PreviewHooks {
  /** Whether previews follow every change (the "live preview" box). */
  live(): boolean;
  /** The label, axis and method to interpolate now. */
  target(): PreviewTarget;
  /** Bring the drawn slices up to date (saving first when `explicit`); the number drawn with contours. */
  prepare(explicit: boolean): Promise<number>;
  /** Show the new result (null: nothing drawn to interpolate). */
  show(label: number, result: InterpResult | null, explicit: boolean): void;
  /** A new result was shown and measured (the 3D view follows it). */
  updated(): void;
  /** A run failed. */
  failed(message: string, explicit: boolean): void;
  /** ms from the change to the preview painted. */
  latency(ms: number): void;
  /** A run ended (either way). */
  settled(): void;
}

/** One preview result per label and axis. */
export class Previews {
  private results = new Map<string, InterpResult>(); // `${label}/${axis}`
  private busy = false;
  private again = false;
  /** When the change the next preview shows was made. */
  private changedAt: number | null = null;

  constructor(
    private api: Api,
    private cellId: string,
    private hooks: PreviewHooks,
  ) {}

  /** The result of a label along an axis, if any. */
  get(label: number, axis: Axis): InterpResult | undefined {
    return this.results.get(`${label}/${axis}`);
  }

  /** Every result with its label. */
  *all(): IterableIterator<[number, InterpResult]> {
    for (const [key, res] of this.results) yield [Number(key.split("/")[0]), res];
  }

  /** A label's result along an axis, interpolated now if there is none yet. */
  async ensure(label: number, axis: Axis, method: string): Promise<InterpResult> {
    let res = this.get(label, axis);
    if (!res) {
      res = await this.api.interpolate(this.cellId, label, axis, { method, preview: true, recommend: !method });
      this.results.set(`${label}/${axis}`, res);
    }
    return res;
  }

  /** A change was made now (the preview latency is measured from here). */
  changed(): void {
    this.changedAt = performance.now();
  }

  /** Whether no run is going on or asked for. */
  get idle(): boolean {
    return !this.busy && !this.again;
  }

  /** Run a preview if the live preview is on. */
  schedule(): void {
    if (!this.hooks.live()) return;
    void this.run(false);
  }

  /** Interpolate the current label along the working axis and show it. */
  async run(explicit: boolean): Promise<void> {
    if (this.busy) {
      this.again = true;
      return;
    }
    this.busy = true;
    const { label, axis, method, confidence } = this.hooks.target();
    const t0 = this.changedAt;
    try {
      const contoursDrawn = await this.hooks.prepare(explicit);
      if (contoursDrawn === 0) {
        this.results.delete(`${label}/${axis}`);
        this.hooks.show(label, null, explicit);
      } else {
        // Only the Interpolate button stores a result; live previews stay in the server's memory.
        // With no method picked the server runs the one leave-one-out recommends.
        const r = await this.api.interpolate(this.cellId, label, axis, {
          method,
          preview: !explicit,
          confidence,
          recommend: !method,
        });
        this.results.set(`${label}/${axis}`, r);
        this.hooks.show(label, r, explicit);
        if (t0 !== null) {
          await new Promise((res) => requestAnimationFrame(() => res(null)));
          this.hooks.latency(performance.now() - t0);
          if (this.changedAt === t0) this.changedAt = null;
        }
        this.hooks.updated();
      }
    } catch (e) {
      this.hooks.failed((e as Error).message, explicit);
    } finally {
      this.busy = false;
      this.hooks.settled();
    }
    if (this.again) {
      this.again = false;
      void this.run(false);
    }
  }
}
