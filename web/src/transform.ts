/**
 * Canvas <-> slice coordinate transforms.
 *
 * A slice point is `(u, v)` in continuous pixel units: pixel `(a, b)` covers
 * `[a, a+1) x [b, b+1)` and its centre is `(a + 0.5, b + 0.5)` (docs/conventions.md).
 * Canvas coordinates are CSS pixels relative to the canvas' top-left corner;
 * the device-pixel ratio is applied only when painting, so pointer positions
 * and drawing share one transform.
 *
 * The map is affine without rotation: `x = u * scale + ox`,
 * `y = v * scale * aspect + oy`, where `aspect = spacing_v / spacing_u` keeps
 * anisotropic voxels physically proportioned (a y- or x-slice of a volume
 * with thick z slices is stretched along v).
 */
export interface ViewTransform {
  /** CSS pixels per slice pixel along u. */
  scale: number;
  /** Physical height / width of one pixel (spacing_v / spacing_u). */
  aspect: number;
  /** Canvas x of slice u = 0. */
  ox: number;
  /** Canvas y of slice v = 0. */
  oy: number;
}

/** A 2-vector. */
export type Vec2 = [number, number];

/** Canvas CSS pixel -> continuous slice coordinates. */
export function canvasToSlice(t: ViewTransform, x: number, y: number): Vec2 {
  return [(x - t.ox) / t.scale, (y - t.oy) / (t.scale * t.aspect)];
}

/** Continuous slice coordinates -> canvas CSS pixel. */
export function sliceToCanvas(t: ViewTransform, u: number, v: number): Vec2 {
  return [u * t.scale + t.ox, v * t.scale * t.aspect + t.oy];
}

/**
 * The pixel `(a, b)` that contains slice point `(u, v)`, or null outside a
 * `width x height` slice. Uses floor, so the pixel's left/top edges belong to
 * it and its right/bottom edges to the next pixel.
 */
export function pixelAt(u: number, v: number, width: number, height: number): Vec2 | null {
  const a = Math.floor(u);
  const b = Math.floor(v);
  if (a < 0 || b < 0 || a >= width || b >= height) return null;
  return [a, b];
}

/**
 * The transform that shows a whole `width x height` slice centred in a
 * `cw x ch` canvas with `margin` CSS pixels on the tighter side.
 */
export function fitTransform(
  width: number,
  height: number,
  aspect: number,
  cw: number,
  ch: number,
  margin = 8,
): ViewTransform {
  const availW = Math.max(1, cw - 2 * margin);
  const availH = Math.max(1, ch - 2 * margin);
  const scale = Math.max(1e-6, Math.min(availW / width, availH / (height * aspect)));
  return {
    scale,
    aspect,
    ox: (cw - width * scale) / 2,
    oy: (ch - height * scale * aspect) / 2,
  };
}

/**
 * Zoom by `factor` about canvas point `(x, y)`: the slice point under it
 * stays under it. The scale is clamped to `[minScale, maxScale]`.
 */
export function zoomAt(
  t: ViewTransform,
  x: number,
  y: number,
  factor: number,
  minScale = 0.05,
  maxScale = 200,
): ViewTransform {
  const scale = Math.min(maxScale, Math.max(minScale, t.scale * factor));
  const [u, v] = canvasToSlice(t, x, y);
  return {
    scale,
    aspect: t.aspect,
    ox: x - u * scale,
    oy: y - v * scale * t.aspect,
  };
}

/** Move the picture by `(dx, dy)` CSS pixels. */
export function panBy(t: ViewTransform, dx: number, dy: number): ViewTransform {
  return { ...t, ox: t.ox + dx, oy: t.oy + dy };
}

/** Axis names. */
export type Axis = "x" | "y" | "z";

/** The volume dims (0 = x, 1 = y, 2 = z) that become u and v on a slice along `axis`. */
export function inPlane(axis: Axis): [number, number] {
  switch (axis) {
    case "x":
      return [1, 2];
    case "y":
      return [0, 2];
    case "z":
      return [0, 1];
  }
}

/** The dim index of an axis. */
export function axisDim(axis: Axis): number {
  return axis === "x" ? 0 : axis === "y" ? 1 : 2;
}

/** Voxel `(i, j, k)` of pixel `(u, v)` on slice `index` along `axis`. */
export function voxelOf(axis: Axis, index: number, u: number, v: number): [number, number, number] {
  switch (axis) {
    case "x":
      return [index, u, v];
    case "y":
      return [u, index, v];
    case "z":
      return [u, v, index];
  }
}

/** `(width, height, depth)` of slices along `axis` for volume dims. */
export function sliceShape(axis: Axis, dims: [number, number, number]): [number, number, number] {
  const [du, dv] = inPlane(axis);
  return [dims[du], dims[dv], dims[axisDim(axis)]];
}
