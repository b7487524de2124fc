/** Entry point of the interslice web UI. */
import "./style.css";
import { App } from "./app";
import { requireElement } from "./dom";

const app = new App(requireElement(document, "#app", HTMLElement));
// A small handle for the end-to-end test and for debugging in the console.
(window as unknown as { __interslice: unknown }).__interslice = {
  app,
  tracer: () => app.current,
};
void app.start();
