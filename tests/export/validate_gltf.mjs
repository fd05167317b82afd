// Validate glTF files with the Khronos glTF Validator (npm package "gltf-validator").
//
// Usage: node validate_gltf.mjs NODE_MODULES_DIR FILE [FILE ...]
// Prints one JSON line per file: {"file", "errors", "warnings", "infos", "hints", "messages"}
// and exits 1 if any file has errors, 2 if the validator cannot run.
import { readFile } from "node:fs/promises";
import { createRequire } from "node:module";
import path from "node:path";

const [modulesDir, ...files] = process.argv.slice(2);
if (!modulesDir || files.length === 0) {
  console.error("usage: node validate_gltf.mjs NODE_MODULES_DIR FILE [FILE ...]");
  process.exit(2);
}

let validator;
try {
  const require = createRequire(path.join(path.resolve(modulesDir), "noop.js"));
  validator = require("gltf-validator");
} catch (error) {
  console.error(`cannot load gltf-validator from ${modulesDir}: ${error.message}`);
  process.exit(2);
}

let failed = false;
for (const file of files) {
  const bytes = new Uint8Array(await readFile(file));
  const report = await validator.validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues: 100,
    externalResourceFunction: (uri) =>
      readFile(path.resolve(path.dirname(file), decodeURIComponent(uri))),
  });
  const issues = report.issues;
  const messages = issues.messages.map((m) => `${m.severity}:${m.code}:${m.pointer ?? ""}:${m.message}`);
  console.log(JSON.stringify({
    file,
    errors: issues.numErrors,
    warnings: issues.numWarnings,
    infos: issues.numInfos,
    hints: issues.numHints,
    messages,
  }));
  if (issues.numErrors > 0) failed = true;
}
process.exit(failed ? 1 : 0);
