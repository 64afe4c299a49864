// Validates .glb/.gltf files with the Khronos glTF validator (npm package `gltf-validator`,
// a library: this script calls its validateBytes). Usage: node gltf-validate.mjs FILE...
// Prints nothing and exits 0 when every file has zero errors; otherwise prints each error
// (and the issue counts) and exits 1. Warnings and infos are printed only with VERBOSE=1.
import { readFileSync } from "node:fs";
import { basename, resolve } from "node:path";
import { createRequire } from "node:module";

const require = createRequire(import.meta.url);
const mod = process.env.GLTF_VALIDATOR_MODULE;
const validator = require(mod ? resolve(mod) : "gltf-validator");

let failed = false;
for (const file of process.argv.slice(2)) {
  const report = await validator.validateBytes(new Uint8Array(readFileSync(file)), {
    uri: basename(file),
    maxIssues: 0,
  });
  const { numErrors, numWarnings, numInfos, messages } = report.issues;
  for (const m of messages) {
    if (m.severity === 0 || process.env.VERBOSE === "1") {
      console.error(`${file}: [${["error", "warning", "info", "hint"][m.severity]}] ${m.code} ${m.pointer ?? ""}: ${m.message}`);
    }
  }
  if (numErrors > 0) {
    failed = true;
    console.error(`${file}: ${numErrors} errors, ${numWarnings} warnings, ${numInfos} infos`);
  } else if (process.env.VERBOSE === "1") {
    console.error(`${file}: 0 errors, ${numWarnings} warnings, ${numInfos} infos`);
  }
}
process.exit(failed ? 1 : 0);
