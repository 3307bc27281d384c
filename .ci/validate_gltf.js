// Validate glTF files with the Khronos glTF validator (npm: gltf-validator):
//     node .ci/validate_gltf.js FILE.glb...
// Prints each file's counts of errors, warnings, infos and hints and every
// message; exits 1 when any file has an error or a warning.
const fs = require("fs");
const validator = require("gltf-validator");

async function main(files) {
    let failed = false;
    for (const file of files) {
        const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)));
        const i = report.issues;
        console.log(`${file}: ${i.numErrors} errors, ${i.numWarnings} warnings, ${i.numInfos} infos, ${i.numHints} hints`);
        for (const m of i.messages) {
            console.log(`  ${m.severity} ${m.code} ${m.pointer || ""}: ${m.message}`);
        }
        if (i.numErrors > 0 || i.numWarnings > 0) {
            failed = true;
        }
    }
    if (files.length === 0) {
        console.error("usage: node validate_gltf.js FILE.glb...");
        failed = true;
    }
    process.exit(failed ? 1 : 0);
}

main(process.argv.slice(2)).catch((e) => {
    console.error(`error: ${e}`);
    process.exit(1);
});
