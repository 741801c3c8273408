// Bundles src/viewer.js with three.js into one minified IIFE the Python package inlines.
import { build } from "esbuild";
import { fileURLToPath } from "node:url";
import path from "node:path";

const here = path.dirname(fileURLToPath(import.meta.url));
const outfile = path.join(here, "..", "python", "kinema", "viewer", "static", "viewer.js");

await build({
  entryPoints: [path.join(here, "src", "viewer.js")],
  bundle: true,
  format: "iife",
  minify: true,
  target: ["es2020"],
  legalComments: "eof",
  outfile,
  logLevel: "info",
});
