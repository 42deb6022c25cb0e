// Validates glTF files with the Khronos glTF-Validator (npm `gltf-validator`).
//
//   node tests/browser/validate.mjs FILE.glb [FILE.glb ...]
//
// Prints one JSON object on stdout:
//   {"validator": "2.0.0-dev.3.10", "reports": [{"file", "errors", "warnings", "infos", "hints", "messages": [...]}]}
// where `messages` lists every issue as {code, severity, pointer, message}
// (severity 0 error, 1 warning, 2 info, 3 hint). Exit status: 0 when no file has
// an error or a warning, 1 when one has, 2 when a file cannot be read or parsed.
import { readFile } from 'node:fs/promises';
import { basename } from 'node:path';
import validator from 'gltf-validator';

const files = process.argv.slice(2);
if (files.length === 0) {
  console.error('usage: node validate.mjs FILE.glb [FILE.glb ...]');
  process.exit(2);
}

const reports = [];
let status = 0;
for (const file of files) {
  let report;
  try {
    const bytes = new Uint8Array(await readFile(file));
    report = await validator.validateBytes(bytes, {
      uri: basename(file),
      maxIssues: 0, // all of them
      writeTimestamp: false,
    });
  } catch (error) {
    console.error(`${file}: ${error}`);
    process.exit(2);
  }
  const issues = report.issues;
  reports.push({
    file,
    errors: issues.numErrors,
    warnings: issues.numWarnings,
    infos: issues.numInfos,
    hints: issues.numHints,
    messages: issues.messages.map(({ code, severity, pointer, message }) => ({ code, severity, pointer, message })),
  });
  if (issues.numErrors > 0 || issues.numWarnings > 0) status = 1;
}
console.log(JSON.stringify({ validator: validator.version(), reports }, null, 1));
process.exit(status);
