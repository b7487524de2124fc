/**
 * The status line under the views: axis and slice, the voxel under the
 * pointer and its value, the label being traced, whether the slice is drawn,
 * drawn empty or interpolated, and the time spent.
 */
import type { Label } from "./api";
import { h, hms } from "./dom";
import type { Axis } from "./transform";

/** What the status line shows. */
export interface Status {
  axis: Axis;
  index: number;
  depth: number;
  /** `(i, j, k)` of the voxel under the pointer, or "—". */
  voxel: string;
  /** Its value, or "—". */
  value: string;
  label: Label;
  /** The slice's drawn state: undefined not drawn, true drawn empty, false drawn. */
  drawn: boolean | undefined;
  /** Slices drawn for the label along the axis. */
  drawnCount: number;
  /** Whether a preview of the label exists (then undrawn slices are interpolated). */
  preview: boolean;
  seconds: number;
}

/** The children of the status line; `help` opens the shortcut help. */
export function statusLine(s: Status, help: () => void): Node[] {
  const kind = s.drawn === undefined ? (s.preview ? "interpolated" : "not drawn") : s.drawn ? "drawn (empty)" : "drawn";
  return [
    h("span", {}, `axis ${s.axis}`),
    h("span", { testid: "status-slice" }, `slice ${s.index} / ${s.depth - 1}`),
    h("span", { testid: "status-voxel" }, `voxel ${s.voxel}`),
    h("span", { testid: "status-value" }, `value ${s.value}`),
    h("span", {}, h("i", { class: "swatch", style: { background: s.label.color } }), ` ${s.label.name}`),
    h(
      "span",
      { testid: "status-kind", class: kind.startsWith("drawn") ? "ok" : "" },
      `${kind} · ${s.drawnCount} drawn`,
    ),
    h("span", { title: "time spent tracing this cell" }, `time ${hms(s.seconds)}`),
    h("span", { class: "grow" }),
    h("button", { class: "link", onclick: help, title: "Keyboard shortcuts (?)" }, "? help"),
  ];
}
