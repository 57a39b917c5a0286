-- Drives `skillc lsp` from Neovim (0.7 and later: vim.lsp.start_client), headless, as an editor
-- user would: hover and go-to-definition on a parameter used in arithmetic, then a change that
-- breaks the file and the diagnostic it brings. tests/lsp_editors.rs runs it with SKILLC, FILE and
-- OUT in the environment and checks what it writes to OUT.
local out = {}
local function log(s) table.insert(out, s) end
local file = os.getenv("FILE")
vim.cmd("edit " .. file)
local buf = vim.api.nvim_get_current_buf()
local id = vim.lsp.start_client({ name = "skillc", cmd = { os.getenv("SKILLC"), "lsp" }, root_dir = vim.fn.fnamemodify(file, ":h") })
vim.lsp.buf_attach_client(buf, id)
vim.wait(3000, function() local c = vim.lsp.get_client_by_id(id); return c and c.initialized end)
local client = vim.lsp.get_client_by_id(id)
log("initialized: " .. tostring(client and client.initialized) .. " offset_encoding: " .. tostring(client and client.offset_encoding))
-- line of `on dwell hold / 2 + hold -> retract`
local lines = vim.api.nvim_buf_get_lines(buf, 0, -1, false)
local row, col
for i, l in ipairs(lines) do local c = l:find("dwell hold") if c then row = i - 1; col = c + 5 end end
local params = { textDocument = { uri = vim.uri_from_bufnr(buf) }, position = { line = row, character = col } }
local r = vim.lsp.buf_request_sync(buf, "textDocument/hover", params, 3000)
for _, res in pairs(r or {}) do log("hover: " .. vim.inspect(res.result and res.result.contents and res.result.contents.value)) end
r = vim.lsp.buf_request_sync(buf, "textDocument/definition", params, 3000)
for _, res in pairs(r or {}) do log("definition: " .. vim.inspect(res.result)) end
-- break the file: `2 mm * hold` and wait for the diagnostic
vim.api.nvim_buf_set_lines(buf, row, row + 1, false, { "        on dwell hold * 2 mm -> retract" })
vim.wait(3000, function() return #vim.diagnostic.get(buf) > 0 end)
for _, d in ipairs(vim.diagnostic.get(buf)) do log(string.format("diagnostic %d:%d %s [%s]", d.lnum + 1, d.col + 1, d.message, tostring(d.code))) end
local f = io.open(os.getenv("OUT"), "w") f:write(table.concat(out, "\n")) f:close()
vim.cmd("qa!")
