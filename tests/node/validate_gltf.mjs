// Validate one .gltf/.glb file with the Khronos glTF validator and print its
// report as JSON on stdout. External resources (.bin buffers, images) are
// loaded from the asset's own folder only; a URI that leaves it is refused.
//
// usage: node validate_gltf.mjs FILE
import fs from "node:fs";
import path from "node:path";
import { validateBytes } from "gltf-validator";

const file = process.argv[2];
if (!file) {
  console.error("usage: node validate_gltf.mjs FILE");
  process.exit(2);
}
const fullpath = path.resolve(file);
const folder = path.dirname(fullpath);

function loadResource(uri) {
  return new Promise((resolve, reject) => {
    const target = path.resolve(folder, decodeURIComponent(uri));
    if (path.relative(folder, target).startsWith("..")) {
      reject(`refusing ${uri}: it leaves ${folder}`);
      return;
    }
    fs.readFile(target, (error, data) => (error ? reject(error.toString()) : resolve(data)));
  });
}

try {
  const report = await validateBytes(new Uint8Array(fs.readFileSync(fullpath)), {
    uri: path.basename(fullpath),
    maxIssues: 0,
    writeTimestamp: false,
    externalResourceFunction: loadResource,
  });
  process.stdout.write(JSON.stringify(report));
} catch (error) {
  console.error(String(error));
  process.exit(1);
}
