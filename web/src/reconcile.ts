/**
 * The tracings the screen shows: the server's contours with the outbox's
 * unacknowledged changes applied on top, and the drawn slices of the label
 * and axis being traced (drawn with contours, or drawn empty). What the user
 * drew shows at once and stays shown while offline; acknowledgements and
 * reloads replace the pending copies with the stored ones.
 */
import { ApiError, type Api, type Contour, type NewContour } from "./api";
import { applyPending, newClientId, type Op, type Outbox } from "./queue";
import type { Axis } from "./transform";

/** Undo and redo wait until every change is saved. */
export class ChangesPending extends Error {
  constructor() {
    super("not connected: undo waits until the changes are saved");
  }
}

/** The label and axis whose drawn slices are tracked. */
export interface Target {
  label: number;
  axis: Axis;
}

/** The reconciled tracings of one cell. */
export class Tracings {
  private serverContours: Contour[] = [];
  /** The server's contours with the pending changes applied. */
  contours: Contour[] = [];
  /** Drawn slices of the target: index → whether drawn empty. */
  drawn = new Map<number, boolean>();

  constructor(
    private api: Api,
    private outbox: Outbox,
    private cellId: string,
    /** Reports that the server cannot be reached. */
    private offline: (msg: string) => void,
  ) {}

  /** Apply the pending changes again (after the outbox changed). */
  recompute(): void {
    this.contours = applyPending(this.serverContours, this.outbox.pending as Op[], this.cellId);
  }

  /** Reload the contours and the target's drawn slices from the server. */
  async reload(t: Target): Promise<void> {
    try {
      this.serverContours = await this.api.contours(this.cellId);
    } catch (e) {
      if (!(e instanceof ApiError)) this.offline("offline: showing unsaved contours only");
    }
    await this.reloadDrawn(t);
    this.recompute();
  }

  /** Reload the target's drawn slices (from the contours when offline), pending changes applied. */
  async reloadDrawn(t: Target): Promise<void> {
    const m = new Map<number, boolean>();
    try {
      for (const d of await this.api.drawn(this.cellId, t.label, t.axis)) m.set(d.index, d.empty);
    } catch {
      for (const c of this.serverContours) if (c.label === t.label && c.axis === t.axis) m.set(c.index, false);
    }
    for (const op of this.outbox.pending) {
      if (op.cell !== this.cellId) continue;
      if (op.kind === "contour" && op.body.label === t.label && op.body.axis === t.axis) m.set(op.body.index, false);
      if (op.kind === "empty" && op.label === t.label && op.axis === t.axis) m.set(op.index, true);
      if (op.kind === "replace" && op.label === t.label && op.axis === t.axis) m.delete(op.index);
    }
    this.drawn = m;
  }

  /** Save a contour of the target (`clientId` makes a retry store it once). */
  add(body: NewContour & Target, clientId: string): void {
    this.drawn.set(body.index, false);
    void this.outbox.push({ kind: "contour", cell: this.cellId, client_id: clientId, body });
  }

  /** Clear the target's contours on slice `index` (undoable on the server). */
  clear(t: Target, index: number): void {
    this.drawn.delete(index);
    const op: Op = { kind: "replace", cell: this.cellId, client_id: newClientId(), ...t, index, contours: [] };
    void this.outbox.push(op);
  }

  /** Mark slice `index` drawn with no contour of the target. */
  markEmpty(t: Target, index: number): void {
    this.drawn.set(index, true);
    void this.outbox.push({ kind: "empty", cell: this.cellId, client_id: newClientId(), ...t, index });
  }

  /**
   * Take an acknowledged operation: a stored contour joins the server's list;
   * anything else needs a reload (returns false then).
   */
  acknowledged(op: Op, answer: unknown): boolean {
    if (op.kind === "contour" && answer && typeof answer === "object" && "id" in answer) {
      const c = answer as Contour;
      if (!this.serverContours.some((x) => x.id === c.id)) this.serverContours.push(c);
      return true;
    }
    return false;
  }

  /**
   * Undo or redo the user's last change on the server once every pending
   * change is saved (then `reload`); false when there was nothing to undo or
   * redo. Fails while changes are still waiting to be saved.
   */
  async undoRedo(which: "undo" | "redo"): Promise<boolean> {
    await this.outbox.flush();
    if (this.outbox.pending.length) throw new ChangesPending();
    const r = which === "undo" ? await this.api.undo(this.cellId) : await this.api.redo(this.cellId);
    return r.changed;
  }

  /** The target's drawn slices, those drawn empty, and its contours (all, and on slice `index`). */
  summary(t: Target, index: number): { drawn: number[]; empty: number[]; contours: number; onSlice: number } {
    const mine = this.contours.filter((c) => c.label === t.label && c.axis === t.axis);
    const sorted = (xs: number[]) => xs.sort((a, b) => a - b);
    return {
      drawn: sorted([...this.drawn.keys()]),
      empty: sorted([...this.drawn].filter(([, e]) => e).map(([i]) => i)),
      contours: mine.length,
      onSlice: mine.filter((c) => c.index === index).length,
    };
  }
}
