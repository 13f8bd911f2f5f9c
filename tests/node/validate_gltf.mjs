// Validate .gltf/.glb files with the Khronos glTF validator and print one
// report per file, as one JSON line each, in the order given. External
// resources (.bin buffers, images) are loaded from each asset's own folder
// only; a URI that leaves it is refused.
//
// usage: node validate_gltf.mjs FILE [FILE ...]
import fs from "node:fs";
import path from "node:path";
import { validateBytes } from "gltf-validator";

const files = process.argv.slice(2);
if (files.length === 0) {
  console.error("usage: node validate_gltf.mjs FILE [FILE ...]");
  process.exit(2);
}

function loader(folder) {
  return (uri) =>
    new Promise((resolve, reject) => {
      const target = path.resolve(folder, decodeURIComponent(uri));
      const relative = path.relative(folder, target);
      if (relative === ".." || relative.startsWith(".." + path.sep) || path.isAbsolute(relative)) {
        reject(`refusing ${uri}: it leaves ${folder}`);
        return;
      }
      fs.readFile(target, (error, data) => (error ? reject(error.toString()) : resolve(data)));
    });
}

for (const file of files) {
  const fullpath = path.resolve(file);
  try {
    const report = await validateBytes(new Uint8Array(fs.readFileSync(fullpath)), {
      uri: path.basename(fullpath),
      maxIssues: 0,
      writeTimestamp: false,
      externalResourceFunction: loader(path.dirname(fullpath)),
    });
    process.stdout.write(JSON.stringify(report) + "\n");
  } catch (error) {
    console.error(`${fullpath}: ${String(error)}`);
    process.exit(1);
  }
}
