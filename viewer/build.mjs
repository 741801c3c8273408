// Bundles src/viewer.js with three.js into one minified IIFE the Python package inlines.
import { build } from "esbuild";
import { fileURLToPath } from "node:url";
import path from "node:path";

const here = path.dirname(fileURLToPath(import.meta.url));
// The bundle is committed (a package installs whole without Node); `node build.mjs OUT`
// writes elsewhere, which tests/test_viewer_bundle.py uses to check the committed one.
const outfile = process.argv[2] ?? path.join(here, "..", "python", "kinema", "viewer", "static", "viewer.js");

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
