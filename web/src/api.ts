/**
 * Typed client of the interslice HTTP API (docs/API.md).
 */
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

/** The signed-in user. */
export interface Me {
  /** User name. */
  name: string;
  /** `tracer`, `reviewer` or `admin`. */
  role: string;
  /** Whether a password is required to sign in. */
  auth_required?: boolean;
}

/** A cell of the queue. */
export interface Cell {
  id: string;
  name: string;
  dims: [number, number, number];
  spacing: [number, number, number];
  unit: string;
  /** Voxel type of the volume (also the slices'). */
  dtype: Dtype;
  status: "not_started" | "in_progress" | "done" | "unreadable";
  /** Seconds this user spent tracing it. */
  seconds: number;
  /** Why the file cannot be read (status "unreadable"); such a cell cannot be opened. */
  error?: string;
}

/** A label (component). */
export interface Label {
  id: number;
  name: string;
  color: string;
}

/** A cell with its range and labels. */
export interface CellDetail extends Cell {
  min: number;
  max: number;
  labels: Label[];
}

/** A stored contour. */
export interface Contour {
  id: number | string;
  label: number;
  axis: Axis;
  index: number;
  points: Vec2[];
  pressure?: number[];
  times_ms?: number[];
  tool?: string;
  author?: string;
  created?: string;
  updated?: string;
}

/** A contour to store. */
export interface NewContour {
  label: number;
  axis: Axis;
  index: number;
  points: Vec2[];
  pressure?: number[];
  times_ms?: number[];
  tool?: string;
  client_id?: string;
}

/** A drawn slice. */
export interface Drawn {
  index: number;
  empty: boolean;
}

/** An interpolation method. */
export interface Method {
  name: string;
  description: string;
}

/** The answer of an interpolation. */
export interface InterpResult {
  result_id: string;
  method: string;
  label: number;
  axis: Axis;
  slices: { index: number; drawn: boolean; contours: Vec2[][] }[];
  /** Physical volume of the interpolated mask. */
  volume: number;
  /** Its unit, already cubed ("µm³"). */
  unit: string;
}

/** A triangle mesh in physical units. */
export interface Mesh {
  vertices: number[];
  indices: number[];
}

/** A raw slice. */
export interface RawSlice {
  width: number;
  height: number;
  dtype: Dtype;
  data: ArrayBuffer;
}

/** An automated segmentation of a cell. */
export interface Segmentation {
  id: string | number;
  name: string;
  method: string;
  params?: unknown;
  created?: string;
}

/** A rating of a segmentation. */
export interface Rating {
  segmentation: string | number;
  score: number;
  comment: string;
  user?: string;
  created?: string;
}

/** Metrics as printed by `interslice evaluate --json`. */
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
    return this.json("POST", "/api/login", password ? { name, password } : { name });
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
  setStatus(id: string, status: Cell["status"]): Promise<unknown> {
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
  /** GET /api/labels */
  labels(): Promise<Label[]> {
    return this.json("GET", "/api/labels");
  }
  /** POST /api/labels */
  addLabel(name: string, color?: string): Promise<Label> {
    return this.json("POST", "/api/labels", color ? { name, color } : { name });
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
  /** POST interpolate. */
  interpolate(id: string, label: number, axis: Axis, method?: string): Promise<InterpResult> {
    return this.json("POST", `/api/cells/${enc(id)}/interpolate`, method ? { label, axis, method } : { label, axis });
  }
  /** GET the mesh of an interpolation result. */
  mesh(id: string, resultId: string): Promise<Mesh> {
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
  segment(
    id: string,
    body: { method: string; classes?: number; smooth?: number; largest_component?: boolean; fill_holes?: boolean },
  ): Promise<Segmentation> {
    return this.json("POST", `/api/cells/${enc(id)}/segmentations`, body);
  }
  /** POST evaluate. */
  evaluate(
    id: string,
    body: { label: number; reference: Record<string, unknown>; test: Record<string, unknown> },
  ): Promise<Metrics> {
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
  rate(id: string, r: Rating): Promise<Rating> {
    return this.json("POST", `/api/cells/${enc(id)}/ratings`, r);
  }
}
