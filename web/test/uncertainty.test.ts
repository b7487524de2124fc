import { describe, expect, it } from "vitest";
import type { InterpResult, PreviewSlice } from "../src/api";
import { exportMethod, methodNote } from "../src/preview";
import { UNCERTAIN_TINT, uncertainTints, type Traced } from "../src/scenes";
import type { Vec2 } from "../src/transform";

const ring: Vec2[][] = [
  [
    [0, 0],
    [4, 0],
    [4, 4],
    [0, 4],
  ],
  [
    [1, 1],
    [1, 3],
    [3, 3],
    [3, 1],
  ],
];

function result(slices: PreviewSlice[], extra: Partial<InterpResult> = {}): InterpResult {
  return {
    result_id: -1,
    method: "shape-auto",
    label: 2,
    axis: "z",
    slices,
    volume: 1,
    unit: "µm³",
    voxels: 1,
    ...extra,
  };
}

const slices: PreviewSlice[] = [
  { index: 0, drawn: true, contours: [] },
  { index: 1, drawn: false, contours: [], uncertain: ring },
  { index: 2, drawn: false, contours: [], uncertain: [] },
  { index: 3, drawn: false, contours: [] },
  { index: 4, drawn: true, contours: [] },
];

function traced(previews: [number, InterpResult][], axis: "x" | "y" | "z" = "z"): Traced {
  return { contours: [], previews, axis, label: 2, colorOf: () => "#fff" };
}

describe("uncertainty tint", () => {
  it("fills the uncertain outlines of a skipped slice together (one even-odd tint)", () => {
    const t = traced([[2, result(slices)]]);
    expect(uncertainTints(t, 1, false)).toEqual([{ polys: ring, color: UNCERTAIN_TINT }]);
  });
  it("paints nothing on drawn slices, sure slices, or slices without outlines", () => {
    const t = traced([[2, result(slices)]]);
    for (const i of [0, 2, 3, 4, 9]) expect(uncertainTints(t, i, false)).toEqual([]);
  });
  it("paints nothing for the traced label on a slice it has just drawn, nor off the working axis", () => {
    expect(uncertainTints(traced([[2, result(slices)]]), 1, true)).toEqual([]);
    expect(uncertainTints(traced([[3, result(slices)]]), 1, true)).toHaveLength(1);
    expect(uncertainTints(traced([[2, result(slices)]], "x"), 1, false)).toEqual([]);
  });
});

describe("method note", () => {
  const three: PreviewSlice[] = [0, 1, 2, 3, 4].map((index) => ({ index, drawn: index % 2 === 0, contours: [] }));
  it("says the image-guided method is used because the image predicts the drawn slices", () => {
    const r = result(three, { method: "image-guided", recommended_method: "image-guided", image_weight: 2 });
    expect(methodNote(r, "")).toBe("image-guided: the image predicts your drawn slices better");
  });
  it("says so too where the walk, not the fusion, reads the image (weight 0)", () => {
    const r = result(three, { method: "image-guided", recommended_method: "image-guided", image_weight: 0 });
    expect(methodNote(r, "")).toBe("image-guided: the image predicts your drawn slices better");
  });
  it("says the shape is used because the image did not help", () => {
    const r = result(three, { recommended_method: "shape-auto", image_weight: 0 });
    expect(methodNote(r, "")).toBe("shape-auto: the image did not help");
  });
  it("says why the image is read on two drawn slices: an edge", () => {
    const r = result(slices.slice(0, 2), { recommended_method: "image-guided", image_weight: 0 });
    expect(methodNote(r, "")).toBe("image-guided: your outlines follow a clear edge in the image");
  });
  it("says the image is tested from the third drawn slice", () => {
    const r = result(slices.slice(0, 2), { recommended_method: "shape-auto", image_weight: 0 });
    expect(methodNote(r, "")).toBe("shape-auto: a third drawn slice lets the image be tested");
  });
  it("is empty with a method picked, or no recommendation", () => {
    const r = result(three, { recommended_method: "shape-auto", image_weight: 0 });
    expect(methodNote(r, "linear")).toBe("");
    expect(methodNote(result(three), "")).toBe("");
    expect(methodNote(undefined, "")).toBe("");
  });
});

describe("export method", () => {
  it("is the picked method, else the image-guided one (per label what the recommendation picks)", () => {
    expect(exportMethod("nearest")).toBe("nearest");
    expect(exportMethod("")).toBe("image-guided");
  });
});
