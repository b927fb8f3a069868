// Renders every display block of a notebook's LaTeX (stdin: the `_repr_latex_` text) with KaTeX,
// strict: any unknown command or unbalanced group throws. Prints the number of blocks rendered.
// Usage: node render_latex.js KATEX_MODULE_PATH < latex.txt
const katex = require(process.argv[2]);
const text = require("fs").readFileSync(0, "utf8");
const blocks = text.split("$$").filter((_, k) => k % 2 === 1);
for (const block of blocks) {
  katex.renderToString(block, { displayMode: true, throwOnError: true, strict: "error" });
}
console.log(blocks.length);
