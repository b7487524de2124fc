/**
 * Typed client of the interslice HTTP API (docs/API.md).
 */
import type { components } from "../generated/api-schema";
import type { Axis, Vec2 } from "./transform";
import { parseDtype, type Dtype } from "./windowing";

/** An error answer of the API (status and the server's one-line message). */
export class ApiError extends Error {
  constructor(
    public status: number,
    message: string,
    /** The parsed JSON body of the answer, when it had one. */
    public body: Record<string, unknown> | null = null,
  ) {
    super(message);
  }
}

/**
 * The request and answer schemas of the server's OpenAPI document, generated
 * by `scripts/gen-api-types.sh` (openapi-typescript) and checked against the
 * binary by `scripts/test-web.sh`, so they cannot drift from the server.
 * Where the document types a field more loosely than the server sends it (a
 * string that is one of a few values, an array that always has three numbers)
 * the types below narrow it and say so. Answers the document has no schema for
 * yet are typed by hand, each marked "no schema".
 */
type Schemas = components["schemas"];

/** The roles the server has (`Me.role` is a string in the document). */
export type Role = "tracer" | "reviewer";

/** The signed-in user (schema `Me`); the answer of sign-in has no `auth_required`. */
export type Me = Omit<Schemas["Me"], "role" | "auth_required"> & {
  role: Role;
  /** Whether a password is required to sign in. */
  auth_required?: boolean;
};

/** A cell's status for the signed-in user; "unreadable" when its file cannot be read. */
export type CellStatus = "not_started" | "in_progress" | "done" | "unreadable";

/**
 * A cell of the queue (schema `CellSummary`), narrowed: `dims` and `spacing`
 * have three numbers, `dtype` is a voxel type the slices come in, `status` a
 * `CellStatus`.
 */
export type Cell = Omit<Schemas["CellSummary"], "dims" | "spacing" | "dtype" | "status"> & {
  dims: [number, number, number];
  spacing: [number, number, number];
  dtype: Dtype;
  status: CellStatus;
};

/** One slice suggested to trace next (`GET .../advice`). No schema. */
export interface Suggestion {
  slice: number;
  /** Wrong voxels tracing it is expected to correct. */
  gain_voxels: number;
  /** The expected rise of the result's Dice from tracing it. */
  dice_gain: number;
  /** The drawn slices around it. */
  between: [number, number];
}

/** Which slices of a label to trace next, best first (`GET .../advice`). No schema. */
export interface Advice {
  axis: Axis;
  drawn: number[];
  suggestions: Suggestion[];
  /** Predicted Dice of the interpolation of the tracing now. */
  predicted_dice: number;
  volume_voxels: number;
}
/** A user's tracing of one label: slices, time and the predicted Dice (schema `TracingSummary`). */
export type TracingSummary = Schemas["TracingSummary"];

/** A label (component). No schema. */
export interface Label {
  id: number;
  name: string;
  color: string;
}

/** A cell with its range and labels (`GET /api/cells/{cell}`). No schema. */
export type CellDetail = Cell & {
  min: number;
  max: number;
  labels: Label[];
  /** Physical origin of voxel (0, 0, 0). */
  origin: [number, number, number];
};

/** A contour to store (schema `AddContour`, with `axis` an `Axis` and points `[u, v]` pairs). */
export type NewContour = Omit<Schemas["AddContour"], "axis" | "points"> & { axis: Axis; points: Vec2[] };

/**
 * A stored contour. No schema. Its id is the server's number, or the client id
 * (a string) while it waits in the outbox.
 */
export type Contour = Omit<NewContour, "client_id"> & {
  id: number | string;
  author?: string;
  created?: string;
  updated?: string;
};

/** A drawn slice. No schema. */
export interface Drawn {
  index: number;
  empty: boolean;
}

/** An interpolation method (schema `MethodInfo`). */
export type Method = Schemas["MethodInfo"];

/** One slice of a preview (schema `PreviewSlice`, contours and uncertain outlines as `[u, v]` pairs). */
export type PreviewSlice = Omit<Schemas["PreviewSlice"], "contours" | "uncertain"> & {
  contours: Vec2[][];
  uncertain?: Vec2[][] | null;
};

/** What an interpolation is asked for besides the mask. */
export interface InterpOptions {
  /** The method ("" or absent: the server's default, or the recommended one with `recommend`). */
  method?: string;
  /** Keep it in the server's memory only (a live preview). */
  preview?: boolean;
  /** Outline the uncertain pixels of the skipped slices. */
  confidence?: boolean;
  /** Ask which method leave-one-out recommends (and use it when no method is named). */
  recommend?: boolean;
}

/** The answer of an interpolation (schema `InterpolateAnswer`, with `axis` an `Axis`). */
export type InterpResult = Omit<Schemas["InterpolateAnswer"], "axis" | "slices"> & {
  axis: Axis;
  slices: PreviewSlice[];
};

/** A triangle mesh in physical units. No schema. */
export interface Mesh {
  vertices: number[];
  indices: number[];
}

/** A raw slice (binary answer; its size and type come in headers). */
export interface RawSlice {
  width: number;
  height: number;
  dtype: Dtype;
  data: ArrayBuffer;
}

/** An automated segmentation of a cell (schema `SegmentationInfo`). */
export type Segmentation = Schemas["SegmentationInfo"];

/** A rating to store (schema `RatingBody`). */
export type NewRating = Schemas["RatingBody"];

/** A stored rating. No schema. */
export type Rating = Required<NewRating> & { id?: number; user?: string; created?: string };

/** Metrics as printed by `interslice evaluate --json`. No schema. */
export type Metrics = Record<string, number | null | string>;

const enc = encodeURIComponent;

/** Fetch wrapper: JSON in/out, `{error}` answers turned into ApiError. */
export class Api {
  constructor(
    public base = "",
    private fetchImpl: typeof fetch = (...a) => fetch(...a),
  ) {}

  private async req(method: string, path: string, body?: unknown, keepalive = false): Promise<Response> {
    const init: RequestInit = { method, credentials: "same-origin", headers: {} };
    if (keepalive) init.keepalive = true;
    if (body !== undefined) {
      init.body = JSON.stringify(body);
      (init.headers as Record<string, string>)["Content-Type"] = "application/json";
    }
    const r = await this.fetchImpl(this.base + path, init);
    if (!r.ok) {
      let msg = `${r.status} ${r.statusText}`;
      let body: Record<string, unknown> | null = null;
      try {
        body = (await r.json()) as Record<string, unknown> | null;
        if (body && typeof body.error === "string") msg = body.error;
      } catch {
        /* not JSON */
      }
      throw new ApiError(r.status, msg, body);
    }
    return r;
  }

  private async json<T>(method: string, path: string, body?: unknown, keepalive = false): Promise<T> {
    const r = await this.req(method, path, body, keepalive);
    if (r.status === 204) return undefined as T;
    const text = await r.text();
    if (!text) return undefined as T;
    try {
      return JSON.parse(text) as T;
    } catch {
      // A proxy's page or a truncated answer: say so instead of a parser message.
      throw new ApiError(r.status, `the server's answer to ${method} ${path} is not JSON`);
    }
  }

  /** POST /api/login */
  login(name: string, password?: string): Promise<Me> {
    const body: Schemas["LoginBody"] = password ? { name, password } : { name };
    return this.json("POST", "/api/login", body);
  }
  /** POST /api/logout */
  logout(): Promise<void> {
    return this.json("POST", "/api/logout");
  }
  /**
   * Whether the server requires a password, as far as known: from `/api/me`
   * (its answer, or the body of its 401 when the server includes
   * `auth_required` there); null when the server did not say.
   */
  authRequired: boolean | null = null;

  /** GET /api/me; null when not signed in. */
  async me(): Promise<Me | null> {
    try {
      const me = await this.json<Me>("GET", "/api/me");
      if (typeof me?.auth_required === "boolean") this.authRequired = me.auth_required;
      return me;
    } catch (e) {
      if (e instanceof ApiError && e.status === 401) {
        const a = e.body?.auth_required;
        if (typeof a === "boolean") this.authRequired = a;
        return null;
      }
      throw e;
    }
  }
  /** GET /api/cells */
  cells(queue = true): Promise<Cell[]> {
    return this.json("GET", `/api/cells${queue ? "?queue=true" : ""}`);
  }
  /** GET /api/cells/{cell} */
  cell(id: string): Promise<CellDetail> {
    return this.json("GET", `/api/cells/${enc(id)}`);
  }
  /** PUT /api/cells/{cell}/status */
  setStatus(id: string, status: CellStatus): Promise<unknown> {
    return this.json("PUT", `/api/cells/${enc(id)}/status`, { status });
  }
  /** GET /api/cells/{cell}/histogram */
  histogram(id: string): Promise<import("./windowing").Histogram> {
    return this.json("GET", `/api/cells/${enc(id)}/histogram`);
  }
  /** GET a raw slice. */
  async slice(id: string, axis: Axis, index: number): Promise<RawSlice> {
    const r = await this.req("GET", `/api/cells/${enc(id)}/slices/${axis}/${index}`);
    const data = await r.arrayBuffer();
    const width = Number(r.headers.get("X-Width"));
    const height = Number(r.headers.get("X-Height"));
    const dtype = parseDtype(r.headers.get("X-Dtype"));
    return { width, height, dtype, data };
  }
  /**
   * POST /api/cells/{cell}/time. `keepalive`: the request outlives the page
   * (when the screen or the tab is closed).
   */
  addTime(id: string, seconds: number, keepalive = false): Promise<{ total_seconds: number }> {
    return this.json("POST", `/api/cells/${enc(id)}/time`, { seconds }, keepalive);
  }
  /** GET the signed-in user's tracing summary of a label on a cell. */
  summary(id: string, label: number, method?: string): Promise<TracingSummary> {
    const m = method ? `&method=${enc(method)}` : "";
    return this.json("GET", `/api/cells/${enc(id)}/summary?label=${label}${m}`);
  }
  /** GET /api/labels */
  labels(): Promise<Label[]> {
    return this.json("GET", "/api/labels");
  }
  /** POST /api/labels */
  addLabel(name: string, color?: string): Promise<Label> {
    const body: Schemas["NewLabel"] = color ? { name, color } : { name };
    return this.json("POST", "/api/labels", body);
  }
  /** GET the user's contours of a cell. */
  contours(id: string, q: { axis?: Axis; index?: number; label?: number } = {}): Promise<Contour[]> {
    const p = new URLSearchParams();
    for (const [k, v] of Object.entries(q)) if (v !== undefined) p.set(k, String(v));
    const qs = p.toString();
    return this.json("GET", `/api/cells/${enc(id)}/contours${qs ? "?" + qs : ""}`);
  }
  /** POST a contour (idempotent with client_id). */
  addContour(id: string, c: NewContour): Promise<Contour> {
    return this.json("POST", `/api/cells/${enc(id)}/contours`, c);
  }
  /** PUT: replace a label's contours on one slice (empty list clears). */
  replaceContours(
    id: string,
    axis: Axis,
    index: number,
    label: number,
    contours: Omit<NewContour, "label" | "axis" | "index">[],
  ): Promise<unknown> {
    return this.json("PUT", `/api/cells/${enc(id)}/slices/${axis}/${index}/contours`, { label, contours });
  }
  /** POST: a drawn slice without the structure. */
  markEmpty(id: string, axis: Axis, index: number, label: number): Promise<unknown> {
    return this.json("POST", `/api/cells/${enc(id)}/slices/${axis}/${index}/empty`, { label });
  }
  /** GET the drawn slices of a label along an axis. */
  drawn(id: string, label: number, axis: Axis): Promise<Drawn[]> {
    return this.json("GET", `/api/cells/${enc(id)}/drawn?label=${label}&axis=${axis}`);
  }
  /** POST undo. */
  undo(id: string): Promise<{ changed: boolean }> {
    return this.json("POST", `/api/cells/${enc(id)}/undo`);
  }
  /** POST redo. */
  redo(id: string): Promise<{ changed: boolean }> {
    return this.json("POST", `/api/cells/${enc(id)}/redo`);
  }
  /** GET /api/methods */
  methods(): Promise<Method[]> {
    return this.json("GET", "/api/methods");
  }
  /**
   * POST interpolate. A `preview` is kept in memory on the server (a
   * negative result id) instead of being stored as a result: the live
   * previews after each pen lift; the Interpolate button stores its result.
   */
  interpolate(id: string, label: number, axis: Axis, o: InterpOptions = {}): Promise<InterpResult> {
    const body: Schemas["InterpolateBody"] = {
      label,
      axis,
      preview: o.preview ?? false,
      confidence: o.confidence ?? false,
      recommend: o.recommend ?? false,
      ...(o.method ? { method: o.method } : {}),
    };
    return this.json("POST", `/api/cells/${enc(id)}/interpolate`, body);
  }
  /** GET the slices of a label to trace next, best first. */
  advice(id: string, label: number, axis: Axis, count = 3, method?: string): Promise<Advice> {
    const m = method ? `&method=${enc(method)}` : "";
    return this.json("GET", `/api/cells/${enc(id)}/advice?label=${label}&axis=${axis}&count=${count}${m}`);
  }
  /** GET the mesh of an interpolation result. */
  mesh(id: string, resultId: number): Promise<Mesh> {
    return this.json("GET", `/api/cells/${enc(id)}/results/${enc(resultId)}/mesh`);
  }
  /** The URL of an export download. */
  exportUrl(id: string, format: string, method?: string): string {
    return `${this.base}/api/cells/${enc(id)}/export?format=${enc(format)}${method ? "&method=" + enc(method) : ""}`;
  }
  /** GET segmentations. */
  segmentations(id: string): Promise<Segmentation[]> {
    return this.json("GET", `/api/cells/${enc(id)}/segmentations`);
  }
  /** POST: compute an automated segmentation. */
  segment(id: string, body: Schemas["SegmentBody"]): Promise<Segmentation> {
    return this.json("POST", `/api/cells/${enc(id)}/segmentations`, body);
  }
  /** POST evaluate. */
  evaluate(id: string, body: Schemas["EvaluateBody"]): Promise<Metrics> {
    return this.json("POST", `/api/cells/${enc(id)}/evaluate`, body);
  }
  /** GET the TN/TP/FP/FN overlay of a slice (u8 per pixel: 0 TN, 1 TP, 2 FP, 3 FN). */
  async overlay(
    id: string,
    axis: Axis,
    index: number,
    label: number,
    segmentation: string | number,
  ): Promise<Uint8Array> {
    const r = await this.req(
      "GET",
      `/api/cells/${enc(id)}/overlay/${axis}/${index}?label=${label}&segmentation=${enc(String(segmentation))}`,
    );
    return new Uint8Array(await r.arrayBuffer());
  }
  /** GET ratings. */
  ratings(id: string): Promise<Rating[]> {
    return this.json("GET", `/api/cells/${enc(id)}/ratings`);
  }
  /** POST a rating. */
  rate(id: string, r: NewRating): Promise<Rating> {
    return this.json("POST", `/api/cells/${enc(id)}/ratings`, r);
  }
}
