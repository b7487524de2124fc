import { defineConfig } from "vitest/config";

// The server embeds web/dist and serves it at "/", the API at "/api".
// `npm run dev` proxies /api to a running `interslice serve` (INTERSLICE_URL).
export default defineConfig({
  base: "/",
  build: {
    outDir: "dist",
    emptyOutDir: true,
    chunkSizeWarningLimit: 800,
  },
  server: {
    proxy: {
      "/api": process.env.INTERSLICE_URL ?? "http://127.0.0.1:8080",
    },
  },
  test: {
    include: ["test/**/*.test.ts"],
    environment: "node",
  },
});
