// test/validate_gltf.js - runs the Khronos glTF validator (the npm package gltf-validator) on
// .glb files and says what it found (docs/export.md, "The validator test").
//
//   node test/validate_gltf.js MODULE_DIR FILE.glb...
//
// MODULE_DIR is the folder npm installed into (npm install --prefix MODULE_DIR gltf-validator);
// without it there, the module is looked for the usual way (NODE_PATH, global folders).
// Exit status: 0 when no file has an error, 1 when one has (its messages printed), 77 when the
// module cannot be loaded (CTest's SKIP_RETURN_CODE: the test is reported as skipped), 2 for
// bad usage or a file that cannot be read.
'use strict';

const fs = require('fs');
const path = require('path');

const args = process.argv.slice(2);
if (args.length < 2) {
    console.error('usage: node validate_gltf.js MODULE_DIR FILE.glb...');
    process.exit(2);
}

let validator;
try {
    validator = require(path.resolve(args[0], 'node_modules', 'gltf-validator'));
} catch (e) {
    try {
        validator = require('gltf-validator');
    } catch (e2) {
        console.error('validate_gltf.js: the npm package gltf-validator is not installed (npm ' +
                      'install --prefix ' + args[0] + ' gltf-validator): skipped');
        process.exit(77);
    }
}

async function main() {
    let failed = false;
    for (const file of args.slice(1)) {
        let bytes;
        try {
            bytes = fs.readFileSync(file);
        } catch (e) {
            console.error(file + ': ' + e.message);
            process.exit(2);
        }
        const report = await validator.validateBytes(new Uint8Array(bytes), {
            uri: path.basename(file),
            maxIssues: 100,
        });
        const n = report.issues;
        console.log(path.basename(file) + ': ' + n.numErrors + ' errors, ' + n.numWarnings +
                    ' warnings, ' + n.numInfos + ' infos, ' + n.numHints + ' hints (' +
                    bytes.length + ' bytes, validator ' + report.validatorVersion + ')');
        for (const m of n.messages) {
            const severity = ['error', 'warning', 'info', 'hint'][m.severity] || m.severity;
            console.log('  ' + severity + ' ' + m.code + ' at ' + m.pointer + ': ' + m.message);
        }
        if (n.numErrors > 0) failed = true;
    }
    process.exit(failed ? 1 : 0);
}

main().catch((e) => {
    console.error('validate_gltf.js: ' + (e && e.stack ? e.stack : e));
    process.exit(1);
});
