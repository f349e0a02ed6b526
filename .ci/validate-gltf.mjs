// Validates glTF/GLB files with the Khronos glTF-Validator (npm package
// gltf-validator). Prints one JSON line per file: {file, errors, warnings,
// messages}; exits 1 if any file has an error.
import { readFileSync } from 'node:fs';
import { createRequire } from 'node:module';
const require = createRequire(import.meta.url);
const validator = require('gltf-validator');

let failed = false;
for (const file of process.argv.slice(2)) {
  const report = await validator.validateBytes(new Uint8Array(readFileSync(file)), {
    maxIssues: 50,
    externalResourceFunction: () => Promise.reject(new Error('external resources are not allowed')),
  });
  const i = report.issues;
  console.log(JSON.stringify({
    file,
    errors: i.numErrors,
    warnings: i.numWarnings,
    messages: i.messages.filter((m) => m.severity <= 1).slice(0, 10),
  }));
  if (i.numErrors > 0) failed = true;
}
process.exit(failed ? 1 : 0);
