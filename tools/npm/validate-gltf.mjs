// Validates glTF/GLB files with the Khronos glTF validator; prints one JSON report per file
// (an array) and exits 1 if any file has errors. Usage: node validate-gltf.mjs FILE...
import { readFile } from "node:fs/promises";
import validator from "gltf-validator";

const reports = [];
let failed = false;
for (const path of process.argv.slice(2)) {
  const bytes = new Uint8Array(await readFile(path));
  const report = await validator.validateBytes(bytes, {
    uri: path,
    maxIssues: 100,
    // A .glb from sitar-scene references nothing outside itself.
    externalResourceFunction: (uri) => Promise.reject(new Error(`external resource ${uri}`)),
  });
  failed ||= report.issues.numErrors > 0;
  reports.push(report);
}
console.log(JSON.stringify(reports, null, 1));
process.exit(failed ? 1 : 0);
