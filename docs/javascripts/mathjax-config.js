// MathJax 3 for pymdownx.arithmatex (generic mode): typeset only what arithmatex marked, \( \) inline and
// \[ \] display.  MathJax itself is the vendored copy javascripts/mathjax/tex-mml-chtml.js (npm mathjax@3,
// copied into the site by docs/gen_ref.py), so pages typeset with no network, also from disk (file://).
window.MathJax = {
  tex: {
    inlineMath: [["\\(", "\\)"]],
    displayMath: [["\\[", "\\]"]],
    processEscapes: true,
    processEnvironments: true
  },
  options: {
    ignoreHtmlClass: ".*|",
    processHtmlClass: "arithmatex",
    enableMenu: false
  }
};
