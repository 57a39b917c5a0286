// Tokenises every shipped .skill file with VS Code's own TextMate engine (vscode-textmate on
// Oniguruma, devDependencies) and fails on any non-space text no rule of the grammar matched.
// Run by hand: `npm install && npm test` in editors/vscode. The offline Rust check is
// tests/lsp_editors.rs; this one confirms it in VS Code's engine.
import fs from "node:fs";
import path from "node:path";
import { fileURLToPath } from "node:url";
import { createRequire } from "node:module";

const require = createRequire(import.meta.url);
const vsctm = require("vscode-textmate");
const oniguruma = require("vscode-oniguruma");

const here = path.dirname(fileURLToPath(import.meta.url));
const repo = path.resolve(here, "../../..");
const wasm = fs.readFileSync(require.resolve("vscode-oniguruma/release/onig.wasm")).buffer;
await oniguruma.loadWASM(wasm);

const registry = new vsctm.Registry({
  onigLib: Promise.resolve({
    createOnigScanner: (patterns) => new oniguruma.OnigScanner(patterns),
    createOnigString: (text) => new oniguruma.OnigString(text),
  }),
  loadGrammar: async (scope) => {
    if (scope !== "source.skill") return null;
    const file = path.join(here, "../syntaxes/skill.tmLanguage.json");
    return vsctm.parseRawGrammar(fs.readFileSync(file, "utf8"), file);
  },
});
const grammar = await registry.loadGrammar("source.skill");

const files = [];
for (const dir of ["stdlib-skills", "examples/tasks", "tests/data/lsp"]) {
  for (const name of fs.readdirSync(path.join(repo, dir)).sort()) {
    if (name.endsWith(".skill")) files.push(path.join(dir, name));
  }
}
let problems = 0;
let tokens = 0;
for (const file of files) {
  const lines = fs.readFileSync(path.join(repo, file), "utf8").split("\n");
  let state = vsctm.INITIAL;
  lines.forEach((line, number) => {
    const result = grammar.tokenizeLine(line, state);
    for (const token of result.tokens) {
      tokens += 1;
      const text = line.slice(token.startIndex, token.endIndex);
      if (token.scopes.length === 1 && text.trim() !== "") {
        problems += 1;
        console.log(`${file}:${number + 1}:${token.startIndex + 1}: unmatched \`${text}\``);
      }
    }
    state = result.ruleStack;
  });
}
console.log(`${files.length} files, ${tokens} tokens, ${problems} unmatched`);
process.exit(problems === 0 && files.length > 0 ? 0 : 1);
