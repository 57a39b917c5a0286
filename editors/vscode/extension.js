// The VS Code extension: starts `skillc lsp` for .skill files (the path is the setting
// `skillc.path`). Highlighting comes from syntaxes/skill.tmLanguage.json without this file.
const vscode = require("vscode");
const { LanguageClient } = require("vscode-languageclient/node");

let client;

function activate(context) {
  const command = vscode.workspace.getConfiguration("skillc").get("path") || "skillc";
  const server = { command, args: ["lsp"] };
  client = new LanguageClient(
    "skillc",
    "skillc language server",
    { run: server, debug: server },
    { documentSelector: [{ scheme: "file", language: "skill" }, { scheme: "untitled", language: "skill" }] }
  );
  context.subscriptions.push(client);
  return client.start();
}

function deactivate() {
  return client ? client.stop() : undefined;
}

module.exports = { activate, deactivate };
