// Validates glTF files with the Khronos glTF Validator: `node validate.mjs FILE...`.
// Prints one JSON line per file: { file, errors, warnings, infos, messages: [code: message] }
// (errors and warnings listed); exits 1 when any file has an error or cannot be read.
import { readFile } from "node:fs/promises";
import validator from "gltf-validator";

let failed = false;
for (const file of process.argv.slice(2)) {
  try {
    const bytes = new Uint8Array(await readFile(file));
    const report = await validator.validateBytes(bytes, {
      uri: file,
      maxIssues: 100,
      externalResourceFunction: (uri) =>
        readFile(new URL(uri, "file://" + file)).then((b) => new Uint8Array(b)),
    });
    const issues = report.issues;
    const messages = issues.messages
      .filter((m) => m.severity <= 1)
      .map((m) => `${m.severity === 0 ? "error" : "warning"} ${m.code} ${m.pointer ?? ""}: ${m.message}`);
    console.log(JSON.stringify({
      file,
      errors: issues.numErrors,
      warnings: issues.numWarnings,
      infos: issues.numInfos,
      messages,
    }));
    if (issues.numErrors > 0) failed = true;
  } catch (e) {
    console.log(JSON.stringify({ file, errors: 1, messages: [`cannot validate: ${e}`] }));
    failed = true;
  }
}
process.exit(failed ? 1 : 0);
