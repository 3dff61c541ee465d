// A small Soar mode for the live cells' editor: tokens of Soar rule files (comments, |strings|,
// <variables>, ^attributes, sp/gp and commands, preferences, the --> arrow), as highlighted
// HTML for the layer under the editor's transparent text. Class names are Pygments' ones, so
// the book's highlighting theme colours them as in the static code blocks.
(function () {
  "use strict";
  const RULES = [
    ["c1", /#[^\n]*/y],                                   // comment
    ["s2", /\|(?:[^|\\]|\\.)*\|?/y],                       // |string|
    ["nv", /<[A-Za-z0-9_*-]+>/y],                          // <variable>
    ["o", /-->|<=>|<>|<=|>=|[@~!=+&-](?=[\s)}])|>(?=[\s)}])|<(?=[\s)}])/y], // arrow, prefs
    ["na", /\^[A-Za-z0-9_*.:-]+/y],                        // ^attribute (and paths)
    ["p", /[{}()]/y],                                      // brackets
    ["mi", /-?\d+(?:\.\d+)?(?=[\s)}]|$)/y],                // number
    ["k", /\b(?:sp|gp|state|impasse)\b/y],                 // keywords
    ["nb", /\b(?:write|crlf|halt|interrupt|dc|concat|make-constant-symbol|timestamp|int|float|abs|div|mod)\b/y],
    ["w", /\s+/y],
    ["n", /[^\s{}()<>^|#]+/y],                             // any other symbol
    ["x", /./y],
  ];
  const COMMANDS = /^(?:source|srand|watch|trace|multi-attributes|max-elaborations|indifferent-selection|decide|learn|chunk|echo|output|excise|init-soar|run|print|matches|preferences|stats|soar|pushd|popd|alias|waitsnc|production)\b/;

  function escape(text) {
    return text.replace(/&/g, "&amp;").replace(/</g, "&lt;").replace(/>/g, "&gt;");
  }

  /** Highlighted HTML of Soar text; the first line of a %%soar cell is the magic's. */
  function highlight(text) {
    let html = "";
    let at = 0;
    if (text.startsWith("%%soar")) {
      const end = text.indexOf("\n") < 0 ? text.length : text.indexOf("\n");
      html += `<span class="cp">${escape(text.slice(0, end))}</span>`;
      at = end;
    }
    let lineStart = true;
    while (at < text.length) {
      if (lineStart) {
        const m = COMMANDS.exec(text.slice(at, at + 40));
        if (m) {
          html += `<span class="k">${escape(m[0])}</span>`;
          at += m[0].length;
          lineStart = false;
          continue;
        }
      }
      for (const [cls, re] of RULES) {
        re.lastIndex = at;
        const m = re.exec(text);
        if (!m || m[0].length === 0) continue;
        const piece = escape(m[0]);
        html += cls === "w" || cls === "x" ? piece : `<span class="${cls}">${piece}</span>`;
        at += m[0].length;
        lineStart = cls === "w" && m[0].includes("\n") && /\n$/.test(m[0]);
        break;
      }
    }
    return html;
  }

  window.SannLive = window.SannLive || {};
  window.SannLive.highlight = highlight;
  window.SannLive.escape = escape;
})();
