// Validate a .gltf with the Khronos glTF validator (npm package
// gltf-validator); prints the issues and exits 1 when there is an error.
// usage: node gltf_validate.js FILE.gltf   (NODE_PATH must find the package)
const fs = require('fs');
const path = require('path');
const validator = require('gltf-validator');

const file = process.argv[2];
const bytes = new Uint8Array(fs.readFileSync(file));
validator
  .validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues: 200,
    externalResourceFunction: () => Promise.reject(new Error('external resources are not expected')),
  })
  .then((report) => {
    console.log(JSON.stringify({validator: report.validatorVersion, issues: report.issues}, null, 1));
    process.exit(report.issues.numErrors > 0 ? 1 : 0);
  })
  .catch((error) => {
    console.error(error);
    process.exit(1);
  });
