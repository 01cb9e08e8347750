// Validates glTF files with the Khronos glTF validator (npm gltf-validator). Fails on any error
// or warning but one: MESH_PRIMITIVE_INVALID_ATTRIBUTE ("Invalid attribute name") on an
// extension-prefixed attribute (KHR_gaussian_splatting:ROTATION and the like), which the
// validator raises for every such name since it does not know the extension (it says so as an
// info, UNSUPPORTED_EXTENSION, not counted). Usage: node validate_gltf.mjs VALIDATOR_DIR FILE...
import { readFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import path from 'node:path';

const [validatorDir, ...files] = process.argv.slice(2);
if (!validatorDir || files.length === 0) {
  console.error('usage: node validate_gltf.mjs VALIDATOR_DIR FILE...');
  process.exit(2);
}
const validator = createRequire(import.meta.url)(path.resolve(validatorDir, 'node_modules/gltf-validator'));

let failed = false;
for (const file of files) {
  const report = await validator.validateBytes(new Uint8Array(readFileSync(file)), {
    uri: file,
    maxIssues: 0,
    externalResourceFunction: (uri) => Promise.resolve(new Uint8Array(readFileSync(path.resolve(path.dirname(file), uri)))),
  });
  const counted = report.issues.messages.filter((m) => m.severity <= 1);  // 0 error, 1 warning
  const unexpected = counted.filter((m) => !(m.code === 'MESH_PRIMITIVE_INVALID_ATTRIBUTE' &&
                                             /\/attributes\/KHR_gaussian_splatting:[A-Z0-9_]+$/.test(m.pointer ?? '')));
  console.log(`${file}: ${report.issues.numErrors} errors, ${report.issues.numWarnings} warnings, ` +
              `${counted.length - unexpected.length} allowed (extension-prefixed attributes), ${unexpected.length} not allowed`);
  for (const m of unexpected) console.log(`  ${m.severity === 0 ? 'error' : 'warning'} ${m.code} at ${m.pointer}: ${m.message}`);
  failed = failed || unexpected.length > 0;
}
process.exit(failed ? 1 : 0);
