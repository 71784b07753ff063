// Builds the console into ../static/, which FastAPI serves. `npm run dev` proxies the
// API and the 3D view (/viser, with its WebSocket) to a `proxima serve` on 127.0.0.1:8000.
import { defineConfig } from "vite";

// The build output is never committed: mark the whole folder ignored from inside it.
const ignoreOutput = {
  name: "proxima-ignore-build-output",
  generateBundle() {
    this.emitFile({
      type: "asset",
      fileName: ".gitignore",
      source: "# Build output of frontend/ (npm run build); never committed.\n*\n",
    });
  },
};

export default defineConfig({
  base: "./",
  plugins: [ignoreOutput],
  build: {
    outDir: "../static",
    emptyOutDir: true,
    sourcemap: false,
  },
  server: {
    host: "127.0.0.1",
    proxy: {
      "/api": { target: "http://127.0.0.1:8000", ws: true },
      "/viser": { target: "http://127.0.0.1:8000", ws: true },
    },
  },
});
