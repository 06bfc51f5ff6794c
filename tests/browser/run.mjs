// CTest entry point: node run.mjs TEST_FILE…
// Exits 77 (CTest SKIP_RETURN_CODE) with a message when Debian Chromium or the viewer's npm
// packages (web/node_modules) are missing; otherwise runs the files with `node --test` and
// passes its exit code on.

import { spawnSync } from 'node:child_process';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

import { paths, skipReason } from './lib/harness.mjs';

const here = path.dirname(fileURLToPath(import.meta.url));
const reason = skipReason();
if (reason) {
  console.log(`SKIP browser tests: ${reason}`);
  process.exit(77);
}
for (const [what, file] of [['rmapd', paths.rmapd], ['rmap-sim', paths.sim]]) {
  try {
    spawnSync(file, ['--help'], { timeout: 10000 });
  } catch {
    console.error(`no ${what} at ${file}`);
    process.exit(1);
  }
}
const files = process.argv.slice(2).map((f) => path.resolve(here, f));
const r = spawnSync(process.execPath, ['--test', '--test-reporter=spec', ...files], { stdio: 'inherit' });
process.exit(r.status === null ? 1 : r.status);
