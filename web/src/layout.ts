/**
 * The page of the tracing screen: the side panel of tools, the four view
 * slots (working view, two side views, 3D), the status line and the help
 * overlay. Every element the screen updates later is made here once and
 * handed back typed in `TracerElements`, so no code looks elements up by
 * name; what the controls do is passed in as `LayoutActions`.
 */
import type { Label, Method } from "./api";
import { clear, h } from "./dom";
import { PROMPT_3D } from "./panel3d";
import { SHORTCUTS, type Action } from "./shortcuts";
import { sliceShape, type Axis } from "./transform";
import { AXES } from "./viewstate";
import type { Preset } from "./windowing";

/** The elements of the tracing screen that change after it is built. */
export interface TracerElements {
  /** The whole screen. */
  root: HTMLDivElement;
  axis: HTMLSelectElement;
  sliceIndex: HTMLInputElement;
  sliceMax: HTMLSpanElement;
  skip: HTMLInputElement;
  label: HTMLSelectElement;
  swatch: HTMLSpanElement;
  newLabel: HTMLInputElement;
  method: HTMLSelectElement;
  /** Which method the preview used and why (with "recommended" chosen). */
  methodNote: HTMLDivElement;
  autoPreview: HTMLInputElement;
  /** "Show uncertainty": tint the preview's least certain pixels. */
  uncertainty: HTMLInputElement;
  /** "n changes not saved yet" / "all changes saved". */
  unsaved: HTMLSpanElement;
  status: HTMLDivElement;
  /** Volume of the last preview. */
  volume: HTMLDivElement;
  /** The next suggested slice, on the working view (click or G goes there). */
  suggest: HTMLButtonElement;
  /** The advice in words: next slice, its gain, predicted Dice, "done" hint. */
  advice: HTMLDivElement;
  /** The "done when" threshold, in % Dice. */
  doneWhen: HTMLInputElement;
  /** Traced slices, time spent and the predicted Dice of the label (`summary.ts`). */
  summary: HTMLDivElement;
  done: HTMLInputElement;
  bright: HTMLInputElement;
  contrast: HTMLInputElement;
  wlo: HTMLInputElement;
  whi: HTMLInputElement;
  preset: HTMLSelectElement;
  /** Slot of the working view. */
  main: HTMLDivElement;
  /** Slots of the other two views. */
  sideA: HTMLDivElement;
  sideB: HTMLDivElement;
  v3d: HTMLDivElement;
  v3dHost: HTMLDivElement;
  v3dMsg: HTMLDivElement;
  help: HTMLDivElement;
}

/** What the controls of the screen do (buttons that have a shortcut run its action). */
export interface LayoutActions {
  run(action: Action): void;
  setAxis(a: Axis): void;
  goto(index: number): void;
  /** The skip box changed; answers the value to show. */
  setSkip(value: number): number;
  setLabel(id: number): void;
  addLabel(): void;
  setMethod(name: string): void;
  /** The "Show uncertainty" box changed. */
  setUncertainty(on: boolean): void;
  setBrightness(v: number): void;
  setContrast(v: number): void;
  choosePreset(id: string): void;
  manualWindow(): void;
  setDone(done: boolean): void;
  showList(): void;
  /** Show the 3D view (a click on its slot). */
  show3d(): void;
  /** The "done when" threshold changed (a fraction of Dice; 0 = off). */
  setDoneWhen(v: number): void;
}

/** The settings the controls start from. */
export interface LayoutStart {
  dims: [number, number, number];
  brightness: number;
  contrast: number;
  done: boolean;
  /** Download links of the exports: format → its URL now (read when clicked: it follows the method menu). */
  exports: [string, () => string][];
  /** The evaluation panel's section. */
  evalPanel: HTMLElement;
  /** The "done when" threshold (a fraction of Dice). */
  doneWhen: number;
  /** Whether "Show uncertainty" starts on. */
  uncertainty: boolean;
}

/** Build the screen. */
export function buildLayout(s: LayoutStart, act: LayoutActions): TracerElements {
  const axis = h("select", {
    testid: "axis-select",
    title: "Axis to trace on (X/Y/Z)",
    onchange: () => act.setAxis(axis.value as Axis),
  });
  for (const a of AXES) axis.append(h("option", { value: a }, `${a} (${sliceShape(a, s.dims)[2]} slices)`));
  const sliceIndex = h("input", {
    testid: "slice-index",
    type: "number",
    min: "0",
    title: "Slice index (0-based); any slice can be reached",
    onchange: () => {
      // Leave the box so the arrow keys step through slices again.
      sliceIndex.blur();
      act.goto(Number(sliceIndex.value));
    },
  });
  const skip = h("input", {
    testid: "skip-step",
    type: "number",
    min: "1",
    title: "Skip: Next/Previous slice jump by this many slices",
    onchange: () => (skip.value = String(act.setSkip(Number(skip.value)))),
  });
  const label = h("select", {
    testid: "label-select",
    title: "Component being traced (1-9)",
    onchange: () => act.setLabel(Number(label.value)),
  });
  const newLabel = h("input", {
    testid: "new-label-name",
    type: "text",
    placeholder: "new component",
    class: "grow",
    "aria-label": "new component name",
    onkeydown: (ev: KeyboardEvent) => {
      if (ev.key === "Enter") act.addLabel();
    },
  });
  const range = (testid: string, title: string, start: number, set: (v: number) => void) => {
    const input = h("input", {
      testid,
      type: "range",
      min: "-100",
      max: "100",
      value: String(start),
      title,
      oninput: () => set(Number(input.value)),
    });
    return input;
  };
  const method = h("select", {
    testid: "method-select",
    title: "Interpolation method",
    onchange: () => act.setMethod(method.value),
  });
  const done = h("input", {
    type: "checkbox",
    id: "cell-done",
    checked: s.done,
    onchange: () => act.setDone(done.checked),
  });
  const preset = h("select", {
    testid: "window-preset",
    title: "Window preset",
    onchange: () => act.choosePreset(preset.value),
  });
  const windowBox = (testid: string, title: string) =>
    h("input", { testid, type: "number", step: "any", title, class: "num", onchange: () => act.manualWindow() });
  const doneWhen = h("input", {
    testid: "done-when",
    type: "number",
    min: "0",
    max: "50",
    step: "0.1",
    class: "num",
    value: String(Math.round(s.doneWhen * 1000) / 10),
    title: "Done when one more slice is predicted to add less Dice than this (%; 0 turns the hint off)",
    onchange: () => {
      const v = Number(doneWhen.value);
      const ok = Number.isFinite(v) && v >= 0 && v <= 50;
      if (!ok) doneWhen.value = "0.5";
      act.setDoneWhen(ok ? v / 100 : 0.005);
    },
  });
  const v3dHost = h("div", { class: "v3d-host" });
  const v3dMsg = h("div", { class: "v3d-msg", testid: "view-3d-status" }, PROMPT_3D);
  const e: Omit<TracerElements, "root"> = {
    axis,
    sliceIndex,
    sliceMax: h("span", { class: "muted" }),
    skip,
    label,
    swatch: h("span", { class: "swatch" }),
    newLabel,
    method,
    methodNote: h("div", { class: "muted small", testid: "method-note" }),
    autoPreview: h("input", { type: "checkbox", checked: true, id: "auto-preview" }),
    uncertainty: h("input", {
      type: "checkbox",
      checked: s.uncertainty,
      id: "show-uncertainty",
      testid: "show-uncertainty",
      title: "Tint the pixels of the preview that are least certain (U)",
      onchange: () => act.setUncertainty(e.uncertainty.checked),
    }),
    unsaved: h("span", { class: "unsaved" }),
    status: h("div", { class: "statusline", testid: "status-line" }),
    volume: h("div", { class: "muted small" }),
    suggest: h(
      "button",
      {
        class: "suggest-badge",
        testid: "suggest-badge",
        title: "The slice to trace next (G goes there)",
        hidden: true,
        onclick: () => act.run("goto-suggested"),
      },
      "",
    ),
    advice: h("div", { class: "small", testid: "advice" }),
    doneWhen,
    summary: h("div", { class: "muted small", testid: "tracing-summary" }),
    done,
    bright: range("brightness", "Brightness", s.brightness, (v) => act.setBrightness(v)),
    contrast: range("contrast", "Contrast", s.contrast, (v) => act.setContrast(v)),
    wlo: windowBox("window-low", "Window low (black), in the file's units"),
    whi: windowBox("window-high", "Window high (white), in the file's units"),
    preset,
    main: h("div", { class: "slot-main" }),
    sideA: h("div", { class: "slot-a" }),
    sideB: h("div", { class: "slot-b" }),
    v3d: h(
      "div",
      {
        class: "slot-3d",
        testid: "view-3d",
        title: "3D view of the interpolated surfaces (D)",
        onclick: () => act.show3d(),
      },
      v3dHost,
      v3dMsg,
    ),
    v3dHost,
    v3dMsg,
    help: buildHelp(),
  };

  const btn = (testid: string | null, text: string, title: string, action: () => void, cls = "") =>
    h("button", { testid: testid ?? undefined, title, class: cls, onclick: () => action() }, text);
  const row = (...children: (Node | string)[]) => h("div", { class: "row" }, ...children);
  const wide = (text: string) => h("label", { class: "w" }, text);

  const side = h(
    "aside",
    { class: "side" },
    h(
      "section",
      {},
      h("h3", {}, "Slice"),
      row(h("label", {}, "Axis "), axis),
      row(
        btn("slice-prev", "◀ Prev", "Previous slice by the skip step (←)", () => act.run("prev-slice")),
        e.sliceIndex,
        e.sliceMax,
        btn("slice-next", "Next ▶", "Next slice by the skip step (→)", () => act.run("next-slice")),
      ),
      row(h("label", {}, "Skip "), e.skip, h("span", { class: "muted small" }, "slices per step")),
    ),
    h(
      "section",
      {},
      h("h3", {}, "Component"),
      row(e.swatch, e.label),
      row(
        newLabel,
        btn("new-label-add", "Add", "Add a component", () => act.addLabel()),
      ),
    ),
    h(
      "section",
      {},
      h("h3", {}, "Contours"),
      h(
        "div",
        { class: "grid2" },
        btn(
          "add-contour",
          "Add contour",
          "Finish the red contour and start another (Enter)",
          () => act.run("add-contour"),
          "primary",
        ),
        btn("clear-contours", "Clear all contours", "Clear this component's contours on this slice (C)", () =>
          act.run("clear-contours"),
        ),
        btn("mark-empty", "Mark empty", "The component is absent on this slice (E)", () => act.run("mark-empty")),
        h("span", {}),
        btn("undo", "↶ Undo", "Undo (Ctrl+Z)", () => act.run("undo")),
        btn("redo", "↷ Redo", "Redo (Ctrl+Shift+Z)", () => act.run("redo")),
      ),
      e.unsaved,
    ),
    h(
      "section",
      {},
      h("h3", {}, "Interpolation"),
      row(e.method),
      e.methodNote,
      row(e.autoPreview, h("label", { for: "auto-preview" }, "live preview on skipped slices")),
      row(e.uncertainty, h("label", { for: "show-uncertainty" }, "Show uncertainty")),
      row(btn("interpolate", "Interpolate", "Interpolate now (I)", () => act.run("interpolate"), "primary")),
      e.volume,
      e.summary,
    ),
    h(
      "section",
      {},
      h("h3", {}, "Next slice"),
      e.advice,
      row(
        btn("goto-suggested", "Go to suggested", "Go to the next suggested slice (G)", () => act.run("goto-suggested")),
      ),
      row(h("label", {}, "done when one more slice adds < "), e.doneWhen, h("span", {}, "% Dice")),
    ),
    h(
      "section",
      {},
      h("h3", {}, "Display"),
      row(wide("Brightness"), e.bright),
      row(wide("Contrast"), e.contrast),
      row(wide("Preset"), e.preset),
      row(wide("Window"), e.wlo, h("span", {}, "–"), e.whi),
      row(
        btn("auto-window", "Auto", "Automatic window from the histogram (W)", () => act.run("auto-window")),
        btn(null, "Fit", "Fit slices to the views (0)", () => act.run("zoom-fit")),
        btn(null, "+", "Zoom in (+)", () => act.run("zoom-in")),
        btn(null, "−", "Zoom out (−)", () => act.run("zoom-out")),
      ),
    ),
    s.evalPanel,
    h(
      "section",
      {},
      h("h3", {}, "Cell"),
      row(e.done, h("label", { for: "cell-done" }, "finished (hide from my queue)")),
      row(
        btn(
          "next-cell",
          "Next cell ▶",
          "Open the next cell in the queue (N); everything is saved",
          () => act.run("next-cell"),
          "primary",
        ),
        btn(null, "All cells", "Back to the cell list", () => act.showList()),
      ),
      h(
        "div",
        { class: "row small" },
        "Export: ",
        ...s.exports.map(([f, url]) =>
          h(
            "a",
            {
              href: url(),
              download: "",
              class: "exp",
              onclick: (ev: MouseEvent) => {
                (ev.currentTarget as HTMLAnchorElement).href = url();
              },
            },
            f,
          ),
        ),
      ),
    ),
  );

  const views = h("div", { class: "views" }, e.main, e.sideA, e.sideB, e.v3d);
  const root = h("div", { class: "tracer" }, side, h("div", { class: "work" }, views, e.status), e.help);
  return { ...e, root };
}

/** The keyboard and pen help (hidden until ? or the status line's link). */
function buildHelp(): HTMLDivElement {
  const rows = SHORTCUTS.map((s) => h("tr", {}, h("td", {}, h("kbd", {}, s.keys)), h("td", {}, s.help)));
  const box = h(
    "div",
    {
      class: "help",
      testid: "help-overlay",
      hidden: true,
      onclick: (e: Event) => {
        if (e.target === box) box.hidden = true;
      },
    },
    h(
      "div",
      { class: "help-box" },
      h("h2", {}, "Keyboard and pen"),
      h("table", {}, ...rows),
      h(
        "p",
        { class: "small" },
        "Draw with the pen, mouse or a finger on the working view. Lift on the start point to close a contour (it turns yellow and is saved); ",
        "lift elsewhere and put the pen down again to restart the red contour; Add contour closes it. ",
        "Pan: middle or right drag, or Space/Alt + drag. Zoom: wheel. Click a small view to move the crosshair there.",
      ),
      h("button", { onclick: () => (box.hidden = true) }, "Close"),
    ),
  );
  return box;
}

/** Fill the label menu (the first nine numbered for their shortcut keys). */
export function fillLabels(sel: HTMLSelectElement, labels: readonly Label[]): void {
  clear(sel);
  labels.forEach((l, n) => sel.append(h("option", { value: String(l.id) }, `${n < 9 ? n + 1 + " · " : ""}${l.name}`)));
}

/**
 * Fill the method menu: first "recommended" (value ""), the method the
 * server's leave-one-out picks per label and axis, then every method (the
 * server lists its default first).
 */
export function fillMethods(sel: HTMLSelectElement, methods: readonly Method[]): void {
  clear(sel);
  sel.append(
    h(
      "option",
      { value: "", title: "image-guided where the image predicts the drawn slices better, else the shape default" },
      "recommended",
    ),
  );
  methods.forEach((m, n) =>
    sel.append(h("option", { value: m.name, title: m.description }, n === 0 ? `${m.name} (default)` : m.name)),
  );
}

/** Fill the preset menu; "Manual" is shown (not chosen) when a window is typed in. */
export function fillPresets(sel: HTMLSelectElement, presets: readonly Preset[]): void {
  clear(sel);
  for (const p of presets) {
    const lw = p.level !== undefined ? ` (L ${p.level} / W ${p.width})` : "";
    sel.append(h("option", { value: p.id }, p.name + lw));
  }
  sel.append(h("option", { value: "manual", disabled: true }, "Manual"));
}
