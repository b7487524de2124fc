/**
 * The outbox: every change to contours goes through a persistent queue so
 * that no stroke is lost on a reload or a dropped connection.
 *
 * Operations are stored in `localStorage` before they are sent, sent in
 * order, and removed only when the server acknowledged them. A contour is
 * posted with a `client_id` made when it was drawn, so a retry after a lost
 * answer stores it once. Replacing and marking empty are idempotent by
 * nature. Network failures and 5xx answers are retried with back-off;
 * 4xx answers (other than 401/408/429) drop the operation and report it.
 */
import { ApiError, type Api, type Contour, type NewContour } from "./api";
import type { Axis } from "./transform";

/** One queued change. */
export type Op =
  | { kind: "contour"; cell: string; client_id: string; body: NewContour }
  | {
      kind: "replace";
      cell: string;
      client_id: string;
      axis: Axis;
      index: number;
      label: number;
      contours: NewContour[];
    }
  | { kind: "empty"; cell: string; client_id: string; axis: Axis; index: number; label: number };

/** Where the queue persists (localStorage in the browser, a Map in tests). */
export interface KV {
  getItem(k: string): string | null;
  setItem(k: string, v: string): void;
}

/** A fresh client id (random, URL-safe). */
export function newClientId(): string {
  const c = globalThis.crypto;
  if (c && typeof c.randomUUID === "function") return c.randomUUID();
  return `c${Date.now().toString(36)}${Math.random().toString(36).slice(2)}`;
}

/**
 * Apply pending (unacknowledged) operations of one cell to the server's
 * contours, so the UI shows what the user drew even while offline.
 * Pending contours get their client id as id.
 */
export function applyPending(server: Contour[], ops: Op[], cell: string): Contour[] {
  let out = server.slice();
  for (const op of ops) {
    if (op.cell !== cell) continue;
    if (op.kind === "contour") {
      if (out.some((c) => c.id === op.client_id)) continue;
      out.push({ ...op.body, id: op.client_id });
    } else {
      out = out.filter((c) => !(c.axis === op.axis && c.index === op.index && c.label === op.label));
      if (op.kind === "replace") {
        op.contours.forEach((c, n) => out.push({ ...c, id: `${op.client_id}/${n}` }));
      }
    }
  }
  return out;
}

/** Whether an error is worth retrying. */
export function retryable(e: unknown): boolean {
  if (e instanceof ApiError) return e.status >= 500 || e.status === 408 || e.status === 429;
  return true; // network error (TypeError: Failed to fetch) or abort
}

/** The persistent, ordered outbox. */
export class Outbox {
  private ops: Op[];
  private running = false;
  private timer: ReturnType<typeof setTimeout> | null = null;
  private backoff = 500;
  /** Called after every change of the queue (length) and on errors. */
  onChange: (pending: number, error?: string) => void = () => {};
  /** Called with each operation the server acknowledged. */
  onSent: (op: Op, answer: unknown) => void = () => {};
  /** Called when the server says the user is not signed in. */
  onUnauthorized: () => void = () => {};

  constructor(
    private api: Api,
    private kv: KV,
    private key = "interslice.outbox.v1",
  ) {
    try {
      this.ops = JSON.parse(kv.getItem(key) ?? "[]") as Op[];
      if (!Array.isArray(this.ops)) this.ops = [];
    } catch {
      this.ops = [];
    }
  }

  /** Pending operations (oldest first). */
  get pending(): readonly Op[] {
    return this.ops;
  }

  private save(): void {
    this.kv.setItem(this.key, JSON.stringify(this.ops));
  }

  /** Queue an operation (persisted at once) and start sending. */
  push(op: Op): Promise<void> {
    this.ops.push(op);
    this.save();
    this.onChange(this.ops.length);
    return this.flush();
  }

  /**
   * Send everything queued, in order. Resolves when the queue is empty or
   * sending stopped on a retryable error (a retry is then scheduled).
   */
  async flush(): Promise<void> {
    if (this.running) {
      // Wait for the running flush to finish.
      await new Promise<void>((res) => {
        const check = () => (this.running ? setTimeout(check, 10) : res());
        check();
      });
      if (this.ops.length === 0) return;
    }
    this.running = true;
    if (this.timer) {
      clearTimeout(this.timer);
      this.timer = null;
    }
    try {
      while (this.ops.length > 0) {
        const op = this.ops[0];
        let answer: unknown;
        try {
          answer = await this.send(op);
        } catch (e) {
          if (e instanceof ApiError && e.status === 401) {
            this.onUnauthorized();
            this.onChange(this.ops.length, e.message);
            return;
          }
          if (retryable(e)) {
            this.onChange(this.ops.length, e instanceof Error ? e.message : String(e));
            this.schedule();
            return;
          }
          // Rejected for good: drop it so it does not block the rest.
          this.ops.shift();
          this.save();
          this.onChange(this.ops.length, `not saved: ${e instanceof Error ? e.message : String(e)}`);
          continue;
        }
        this.ops.shift();
        this.save();
        this.backoff = 500;
        this.onSent(op, answer);
        this.onChange(this.ops.length);
      }
    } finally {
      this.running = false;
    }
  }

  private schedule(): void {
    if (this.timer) return;
    const wait = this.backoff;
    this.backoff = Math.min(15000, this.backoff * 2);
    this.timer = setTimeout(() => {
      this.timer = null;
      void this.flush();
    }, wait);
  }

  private send(op: Op): Promise<unknown> {
    switch (op.kind) {
      case "contour":
        return this.api.addContour(op.cell, { ...op.body, client_id: op.client_id });
      case "replace":
        return this.api.replaceContours(
          op.cell,
          op.axis,
          op.index,
          op.label,
          op.contours.map((c) => ({ points: c.points, pressure: c.pressure, times_ms: c.times_ms, tool: c.tool })),
        );
      case "empty":
        return this.api.markEmpty(op.cell, op.axis, op.index, op.label);
    }
  }
}
