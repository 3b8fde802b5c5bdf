// Validates Kubernetes objects (a JSON array on stdin) against the API's schemas with the
// kubernetes-models package: one line per object, and exit 1 if any is invalid. There is no
// cluster here to ask; these are the schemas the API server would apply.
"use strict";
const input = require("fs").readFileSync(0, "utf8");
let failed = 0;
for (const object of JSON.parse(input)) {
  const [group, version] = object.apiVersion.includes("/")
    ? object.apiVersion.split("/")
    : [null, object.apiVersion];
  const path = "kubernetes-models/" + (group ? group + "/" : "") + version + "/" + object.kind;
  const name = `${object.kind} ${object.metadata && object.metadata.name}`;
  try {
    const Model = require(path)[object.kind];
    new Model(object).validate();
    console.log(`valid: ${name} (${object.apiVersion})`);
  } catch (e) {
    failed++;
    console.log(`INVALID: ${name} (${object.apiVersion}): ${e.message}`);
  }
}
process.exit(failed ? 1 : 0);
