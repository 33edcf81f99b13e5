// Runs the Khronos glTF-Validator (npm package gltf-validator) over .glb/.gltf files and prints
// one line per file: "<file>: N errors, N warnings, N infos, N hints". External resources
// (the lightmap PNG previews) are read relative to each file. Exit status 1 when any file has an
// error (or cannot be read), else 0. Usage: node gltf_validate.mjs VALIDATOR_DIR FILE...
import { readFile } from 'node:fs/promises';
import { dirname, join, resolve } from 'node:path';
import { createRequire } from 'node:module';

const [validatorDir, ...files] = process.argv.slice(2);
const validator = createRequire(join(resolve(validatorDir), 'package.json'))('gltf-validator');
let failed = false;
for (const file of files) {
  try {
    const report = await validator.validateBytes(new Uint8Array(await readFile(file)), {
      uri: file,
      maxIssues: 1000,
      externalResourceFunction: (uri) => readFile(join(dirname(file), decodeURIComponent(uri))).then((b) => new Uint8Array(b)),
    });
    const n = report.issues;
    console.log(`${file}: ${n.numErrors} errors, ${n.numWarnings} warnings, ${n.numInfos} infos, ${n.numHints} hints`);
    for (const m of n.messages.filter((m) => m.severity <= 1).slice(0, 20))
      console.log(`  ${m.severity === 0 ? 'error' : 'warning'} ${m.code} at ${m.pointer ?? ''}: ${m.message}`);
    if (n.numErrors > 0) failed = true;
  } catch (e) {
    console.log(`${file}: cannot validate: ${e}`);
    failed = true;
  }
}
process.exit(failed ? 1 : 0);
