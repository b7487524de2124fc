/**
 * The per-cell view settings of the tracing screen (axis, focus, skip step,
 * label, method ("" = the recommended one), display window, uncertainty
 * tint), kept in `localStorage` so a reload returns
 * to the same place. Anything stored that no longer fits the cell (a label
 * that is gone, a focus outside the volume) falls back to the default.
 */
import type { Label } from "./api";
import type { Axis } from "./transform";
import type { Window } from "./windowing";

/** The three axes, in index order. */
export const AXES: readonly Axis[] = ["x", "y", "z"];

/** Persisted per-cell view settings. */
export interface ViewState {
  axis: Axis;
  focus: [number, number, number];
  skip: number;
  label: number;
  method: string;
  brightness: number;
  contrast: number;
  /** The base window: a preset id, or "manual" for `manual`. Empty: the cell's default preset. */
  preset: string;
  /** The window typed in by hand (with preset "manual"). */
  manual: Window | null;
  /** "Show uncertainty": tint the preview's least certain pixels (off by default, docs/web-ui.md says why). */
  uncertainty: boolean;
}

/** Where the settings are kept (localStorage in the browser). */
export interface ViewStore {
  getItem(k: string): string | null;
  setItem(k: string, v: string): void;
}

function key(cellId: string): string {
  return `interslice.view.${cellId}`;
}

/** The stored settings of a cell, made valid for its dimensions and labels. */
export function loadViewState(
  store: ViewStore,
  cellId: string,
  dims: readonly [number, number, number],
  labels: readonly Label[],
): ViewState {
  const d = dims;
  const def: ViewState = {
    axis: "z",
    focus: [Math.floor(d[0] / 2), Math.floor(d[1] / 2), Math.floor(d[2] / 2)],
    skip: 5,
    label: labels.find((l) => /nucleus/i.test(l.name))?.id ?? labels[0].id,
    method: "",
    brightness: 0,
    contrast: 0,
    preset: "",
    manual: null,
    uncertainty: false,
  };
  try {
    const s = JSON.parse(store.getItem(key(cellId)) ?? "null") as Partial<ViewState> | null;
    if (s && typeof s === "object") {
      const m = { ...def, ...s };
      if (!AXES.includes(m.axis)) m.axis = "z";
      m.focus = m.focus.map((f, i) => Math.min(d[i] - 1, Math.max(0, Math.round(Number(f) || 0)))) as [
        number,
        number,
        number,
      ];
      m.skip = Math.max(1, Math.round(Number(m.skip) || 1));
      if (!labels.some((l) => l.id === m.label)) m.label = def.label;
      const mw = m.manual;
      if (!(mw && Number.isFinite(mw.lo) && Number.isFinite(mw.hi) && mw.hi > mw.lo)) m.manual = null;
      if (typeof m.preset !== "string" || (m.preset === "manual" && !m.manual)) m.preset = "";
      if (typeof m.method !== "string") m.method = "";
      m.uncertainty = m.uncertainty === true;
      return m;
    }
  } catch {
    /* fall back to defaults */
  }
  return def;
}

/** Keep the settings of a cell. */
export function saveViewState(store: ViewStore, cellId: string, st: ViewState): void {
  store.setItem(key(cellId), JSON.stringify(st));
}
