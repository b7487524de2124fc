/**
 * The application shell: sign-in, the cell list (this user's queue) and the
 * tracing screen, routed by the URL hash (`#/cells`, `#/cell/<id>`) so a
 * reload returns to the same place.
 */
import { Api, ApiError, type Cell, type Me } from "./api";
import { h, hms } from "./dom";
import { Outbox } from "./queue";
import { Tracer } from "./tracer";

const STATUS_TEXT: Record<Cell["status"], string> = {
  not_started: "not started",
  in_progress: "in progress",
  done: "done",
  unreadable: "cannot be read",
};

/** The app. */
export class App {
  readonly api = new Api("");
  readonly outbox: Outbox;
  private me: Me | null = null;
  private tracer: Tracer | null = null;
  private header: HTMLElement;
  private body: HTMLElement;
  private toastEl: HTMLElement;

  constructor(root: HTMLElement) {
    this.outbox = new Outbox(this.api, window.localStorage);
    this.outbox.onSent = (op, answer) => this.tracer?.onSent(op, answer);
    this.outbox.onChange = (n, err) => {
      this.tracer?.onQueue(n, err);
      if (err && !/retry|fetch|network/i.test(err) && err.startsWith("not saved")) this.toast(err, true);
    };
    this.outbox.onUnauthorized = () => {
      this.me = null;
      void this.route();
    };
    this.header = h("header", { class: "top" });
    this.body = h("main", { class: "body" });
    this.toastEl = h("div", { class: "toast", hidden: true, role: "status" });
    root.append(this.header, this.body, this.toastEl);
    window.addEventListener("hashchange", () => void this.route());
    window.addEventListener("online", () => void this.outbox.flush());
    window.addEventListener("beforeunload", () => this.tracer?.dispose());
  }

  /** Start: find out who is signed in, then show the screen of the URL. */
  async start(): Promise<void> {
    try {
      this.me = await this.api.me();
    } catch (e) {
      this.showError(`cannot reach the server: ${(e as Error).message}`);
      return;
    }
    if (this.me) void this.outbox.flush();
    await this.route();
  }

  private renderHeader(cellName?: string): void {
    const parts: Node[] = [h("a", { href: "#/cells", class: "brand" }, "interslice")];
    if (cellName) parts.push(h("span", { class: "crumb" }, "›  ", cellName));
    parts.push(h("span", { class: "grow" }));
    if (this.me) {
      parts.push(h("span", { class: "who", testid: "current-user" }, `${this.me.name} (${this.me.role})`));
      parts.push(h("button", { class: "link", onclick: () => void this.logout() }, "Sign out"));
    }
    this.header.replaceChildren(...parts);
  }

  private async route(): Promise<void> {
    const hash = location.hash || "#/cells";
    if (this.tracer) {
      this.tracer.dispose();
      this.tracer = null;
    }
    if (!this.me) {
      this.renderHeader();
      return this.showLogin();
    }
    const m = /^#\/cell\/(.+)$/.exec(hash);
    if (m) return this.showCell(decodeURIComponent(m[1]));
    return this.showList();
  }

  private showLogin(): void {
    // The server says whether it needs a password (in /api/me); if it did not, a
    // loopback address needs only a name, as docs/API.md says.
    const host = location.hostname;
    const loopback = host === "127.0.0.1" || host === "localhost" || host === "::1" || host === "[::1]";
    const authRequired = this.api.authRequired ?? !loopback;
    const name = h("input", {
      testid: "user-name",
      type: "text",
      placeholder: "your name",
      autocomplete: "username",
      required: true,
    });
    const pass = h("input", {
      testid: "user-password",
      type: "password",
      placeholder: authRequired ? "password" : "password (if your account has one)",
      autocomplete: "current-password",
    });
    const err = h("p", { class: "err", testid: "login-error" });
    const passLabel = h("label", { hidden: !authRequired }, "Password", pass);
    const form = h(
      "form",
      {
        class: "login",
        testid: "login-form",
        onsubmit: async (e: Event) => {
          e.preventDefault();
          err.textContent = "";
          try {
            this.me = await this.api.login(name.value.trim(), pass.value || undefined);
            void this.outbox.flush();
            if (!location.hash.startsWith("#/cell/")) location.hash = "#/cells";
            await this.route();
          } catch (ex) {
            if (ex instanceof ApiError && ex.status === 401 && !pass.value) {
              // The server wants a password it had not announced: ask for it.
              passLabel.hidden = false;
              pass.placeholder = "password";
              err.textContent = ex.message;
              pass.focus();
            } else {
              err.textContent =
                ex instanceof ApiError && ex.status === 401 ? "wrong name or password" : (ex as Error).message;
            }
          }
        },
      },
      h("h1", {}, "interslice"),
      h("p", { class: "muted" }, "Trace a few slices, interpolate the rest, measure."),
      h("label", {}, "Name", name),
      passLabel,
      h("button", { type: "submit", class: "primary", testid: "sign-in" }, "Sign in"),
      err,
    );
    this.body.replaceChildren(form);
    name.focus();
  }

  /** The cell list. */
  async showList(): Promise<void> {
    if (location.hash !== "#/cells") history.replaceState(null, "", "#/cells");
    this.renderHeader();
    const showAll = h("input", { type: "checkbox", id: "show-done" });
    const list = h("table", { class: "cells", testid: "cell-list" });
    const fill = async () => {
      let cells: Cell[];
      try {
        cells = await this.api.cells(!showAll.checked);
      } catch (e) {
        list.replaceChildren(h("tr", {}, h("td", { class: "err" }, (e as Error).message)));
        return;
      }
      list.replaceChildren(
        h(
          "thead",
          {},
          h(
            "tr",
            {},
            h("th", {}, "Cell"),
            h("th", {}, "Size (voxels)"),
            h("th", {}, "Voxel"),
            h("th", {}, "Type"),
            h("th", {}, "Your status"),
            h("th", {}, "Time spent"),
            h("th", {}),
          ),
        ),
        h(
          "tbody",
          {},
          ...cells.map((c) =>
            c.error !== undefined
              ? h(
                  "tr",
                  { "data-cell": c.id, class: "st-unreadable" },
                  h("td", {}, c.name || c.id),
                  h("td", { colspan: 3, class: "err", testid: `cell-error-${c.id}` }, c.error),
                  h("td", {}, h("span", { class: "badge unreadable" }, STATUS_TEXT.unreadable)),
                  h("td", {}),
                  h("td", {}),
                )
              : h(
                  "tr",
                  { "data-cell": c.id, class: `st-${c.status}` },
                  h(
                    "td",
                    {},
                    h("a", { href: `#/cell/${encodeURIComponent(c.id)}`, testid: `open-cell-${c.id}` }, c.name || c.id),
                  ),
                  h("td", {}, c.dims.join(" × ")),
                  h("td", {}, `${c.spacing.map((s) => +s.toPrecision(3)).join(" × ")} ${c.unit}`),
                  h("td", {}, c.dtype),
                  h("td", {}, h("span", { class: `badge ${c.status}` }, STATUS_TEXT[c.status] ?? c.status)),
                  h("td", { class: "num" }, c.seconds > 0 ? hms(c.seconds) : "—"),
                  h(
                    "td",
                    {},
                    h(
                      "a",
                      { href: `#/cell/${encodeURIComponent(c.id)}`, class: "button" },
                      c.status === "not_started" ? "Start" : "Open",
                    ),
                  ),
                ),
          ),
        ),
      );
      if (cells.length === 0)
        list.append(
          h(
            "tr",
            {},
            h(
              "td",
              { colspan: 7, class: "muted" },
              showAll.checked ? "No cells." : "All your cells are finished. Tick “show finished” to see them.",
            ),
          ),
        );
    };
    showAll.addEventListener("change", () => void fill());
    this.body.replaceChildren(
      h(
        "section",
        { class: "list" },
        h("h2", {}, "Your cells"),
        h("p", { class: "row small" }, showAll, h("label", { for: "show-done" }, "show finished cells")),
        list,
      ),
    );
    await fill();
  }

  private async showCell(id: string): Promise<void> {
    this.body.replaceChildren(h("p", { class: "muted pad" }, "loading…"));
    try {
      const cell = await this.api.cell(id);
      this.renderHeader(cell.name || cell.id);
      const tracer = new Tracer(
        {
          api: this.api,
          outbox: this.outbox,
          me: this.me!,
          openCell: (c) => (location.hash = `#/cell/${encodeURIComponent(c)}`),
          showList: () => (location.hash = "#/cells"),
          toast: (m, e) => this.toast(m, e),
        },
        cell,
      );
      this.tracer = tracer;
      this.body.replaceChildren(tracer.root);
      await tracer.start();
      tracer.onQueue(this.outbox.pending.length);
    } catch (e) {
      if (e instanceof ApiError && e.status === 401) {
        this.me = null;
        return this.route();
      }
      this.showError(`cell ${id}: ${(e as Error).message}`);
    }
  }

  private async logout(): Promise<void> {
    await this.outbox.flush();
    try {
      await this.api.logout();
    } catch {
      /* signed out anyway */
    }
    this.me = null;
    location.hash = "#/cells";
    await this.route();
  }

  private showError(msg: string): void {
    this.body.replaceChildren(h("p", { class: "err pad" }, msg));
  }

  /** A short message at the bottom of the screen. */
  toast(msg: string, error = false): void {
    this.toastEl.textContent = msg;
    this.toastEl.className = error ? "toast error" : "toast";
    this.toastEl.hidden = false;
    clearTimeout((this.toastEl as unknown as { _t?: number })._t);
    (this.toastEl as unknown as { _t?: number })._t = window.setTimeout(
      () => (this.toastEl.hidden = true),
      error ? 6000 : 2500,
    );
  }

  /** The tracing screen, when open (test hook). */
  get current(): Tracer | null {
    return this.tracer;
  }
}
