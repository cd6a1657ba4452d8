// Runs a Python file under MicroPython's WebAssembly build in Node.
// usage: node mpy_run.mjs <micropython.mjs> <script.py> <file.py>...   (files go to /lib)
import { readFileSync } from "node:fs";
import { basename } from "node:path";

const [modPath, script, ...files] = process.argv.slice(2);
const { loadMicroPython } = await import(modPath);
const chunks = [];
const out = () => Buffer.concat(chunks.map((c) => Buffer.from(typeof c === "string" ? Buffer.from(c) : c)));
const mp = await loadMicroPython({ stdout: (d) => { chunks.push(d); }, linebuffer: false, heapsize: 8 * 1024 * 1024 });
try { mp.FS.mkdir("/lib"); } catch (e) { /* exists */ }
for (const f of files) mp.FS.writeFile("/lib/" + basename(f), readFileSync(f));
try {
  mp.runPython("import sys\nsys.path.insert(0, '/lib')\n" + readFileSync(script, "utf8"));
} catch (e) {
  process.stdout.write(out());
  process.stderr.write(String(e) + "\n");
  process.exit(1);
}
process.stdout.write(out());
