// The live book: every Soar code block of the page becomes a live cell (class sann-live) with
// Run, Edit, Reset, Step and Stop buttons, an editor (class sann-live-editor: a textarea over
// a highlighted layer) and an output (class sann-live-output). Cells are found through the
// hidden metadata elements book/live_ext.py puts before each block. Runs go to one Web Worker
// per page (worker.mjs: the engine on Pyodide), started at the first Run; Stop terminates it
// (Python cannot be interrupted from outside a running call), and the next request starts a
// new one. A page opened from disk (file://) cannot start workers, so it says how to serve
// the book instead.
(function () {
  "use strict";
  const script = document.currentScript;
  const BASE = new URL("./", script ? script.src : window.location.href);
  const TRACE_LEVELS = [["0", "no trace"], ["1", "decisions"], ["2", "phases"],
                        ["3", "firings"], ["4", "WM changes"], ["5", "preferences"]];
  const DEFAULT_DECISIONS = 10000;
  const cells = [];
  let worker = null;
  let nextId = 1;
  const pending = new Map();

  /** A request that never got its answer because Stop terminated the worker. */
  class Stopped extends Error {}

  function request(op, body) {
    if (!worker) {
      worker = new Worker(new URL("worker.mjs", BASE), { type: "module" });
      worker.onmessage = (event) => {
        const { id, answer, failure } = event.data;
        const waiting = pending.get(id);
        pending.delete(id);
        if (waiting) failure ? waiting.reject(new Error(failure)) : waiting.resolve(answer);
      };
      worker.onerror = (event) => {
        for (const waiting of pending.values()) waiting.reject(new Error(event.message || "the worker failed"));
        pending.clear();
      };
    }
    const id = nextId++;
    return new Promise((resolve, reject) => {
      pending.set(id, { resolve, reject });
      worker.postMessage({ id, op, request: body });
    });
  }

  /** Terminate the worker: every waiting request fails as Stopped, and every cell forgets
   *  its agent and stepping state, which lived in the worker. */
  function stopWorker() {
    if (!worker) return;
    worker.terminate();
    worker = null;
    for (const waiting of pending.values()) waiting.reject(new Stopped("stopped"));
    pending.clear();
    for (const cell of cells) if (cell) cell.stepping = false;
  }

  function button(text, title, onClick) {
    const b = document.createElement("button");
    b.type = "button";
    b.textContent = text;
    b.title = title;
    b.className = "sann-live-button";
    b.addEventListener("click", onClick);
    return b;
  }

  function element(tag, className, text) {
    const e = document.createElement(tag);
    if (className) e.className = className;
    if (text !== undefined) e.textContent = text;
    return e;
  }

  class LiveCell {
    constructor(meta, block) {
      this.meta = meta;
      this.block = block;
      this.key = `sann-live:${meta.page}:${meta.index}`;
      this.previousTags = null;
      this.stepping = false;
      this.build();
      const saved = window.localStorage.getItem(this.key);
      if (saved !== null && saved !== meta.shipped) {
        this.openEditor();
        this.setText(saved);
        this.note("Your edit from an earlier visit (Reset restores the book's text).");
      }
    }

    build() {
      const root = (this.root = element("div", "sann-live"));
      root.dataset.kind = this.meta.kind;
      if (this.meta.exercise) root.dataset.exercise = this.meta.exercise;
      this.block.parentNode.insertBefore(root, this.block);
      root.appendChild(this.block);
      const wrap = (this.editorWrap = element("div", "sann-live-editor-wrap"));
      wrap.hidden = true;
      this.layer = element("pre", "sann-live-layer highlight");
      this.editor = element("textarea", "sann-live-editor");
      this.editor.spellcheck = false;
      this.editor.setAttribute("aria-label", "Soar rules of this cell");
      this.editor.addEventListener("input", () => this.edited());
      this.editor.addEventListener("keydown", (event) => {
        if (event.key === "Enter" && (event.ctrlKey || event.metaKey)) {
          event.preventDefault();
          this.run();
        } else if (event.key === "Tab" && !event.shiftKey) {
          event.preventDefault();
          this.editor.setRangeText("   ", this.editor.selectionStart, this.editor.selectionEnd, "end");
          this.edited();
        }
      });
      wrap.append(this.layer, this.editor);
      root.appendChild(wrap);

      const bar = element("div", "sann-live-bar");
      this.runButton = button("Run", "Run this cell in the page (Ctrl+Enter in the editor)", () => this.run());
      this.editButton = button("Edit", "Edit the rules of this cell", () => this.openEditor(true));
      this.resetButton = button("Reset", "Back to the book's text", () => this.reset());
      this.phaseButton = button("Step phase", "Run one phase of the decision cycle", () => this.step("phase"));
      this.decisionButton = button("Step decision", "Run one decision cycle", () => this.step("decision"));
      this.stopButton = button("Stop", "Stop the run: ends the page's Python worker, with every cell's agent " +
                               "(the next Run starts a new one)", () => stopWorker());
      this.stopButton.classList.add("sann-live-stop");
      this.stopButton.disabled = true;
      this.trace = element("select", "sann-live-trace");
      this.trace.title = "Trace level (watch)";
      for (const [value, label] of TRACE_LEVELS) {
        const option = element("option", "", `trace ${value}: ${label}`);
        option.value = value;
        this.trace.appendChild(option);
      }
      this.trace.value = this.meta.kind === "exercise" ? "0" : "1";
      this.limit = element("input", "sann-live-limit");
      this.limit.type = "number";
      this.limit.min = "1";
      this.limit.value = String(DEFAULT_DECISIONS);
      this.limit.title = "Decision limit: a run stops there if the rules never halt";
      const limitLabel = element("label", "sann-live-limit-label", "limit ");
      limitLabel.appendChild(this.limit);
      bar.append(this.runButton, this.editButton, this.resetButton, this.phaseButton,
                 this.decisionButton, this.stopButton, this.trace, limitLabel);
      const looks = element("span", "sann-live-looks");
      const LOOKS = [["print S1", "print --depth 2 S1"], ["output-link", "print --depth 3 I3"],
                     ["matches", "matches"], ["preferences", "preferences"]];
      for (const [label, command] of LOOKS) {
        looks.appendChild(button(label, `${command}, after the last run or step`, () => this.query(command)));
      }
      bar.appendChild(looks);
      this.status = element("span", "sann-live-status");
      bar.appendChild(this.status);
      if (this.meta.input_note) bar.appendChild(element("span", "sann-live-input-note", `(${this.meta.input_note})`));
      root.appendChild(bar);

      this.output = element("div", "sann-live-output");
      this.output.hidden = true;
      root.appendChild(this.output);
      this.stepView = element("div", "sann-live-stepview");
      this.stepView.hidden = true;
      root.appendChild(this.stepView);
    }

    text() {
      return this.editorWrap.hidden ? this.meta.shipped : this.editor.value;
    }

    setText(text) {
      this.editor.value = text;
      this.edited();
    }

    openEditor(focus) {
      if (this.editorWrap.hidden) {
        this.editor.value = this.meta.shipped;
        this.editorWrap.hidden = false;
        this.block.hidden = true;
        this.edited();
      }
      if (focus) this.editor.focus();
    }

    edited(errorLine) {
      const text = this.editor.value;
      const lines = text.split("\n");
      let html = window.SannLive.highlight(text);
      if (errorLine) {
        const parts = html.split("\n");
        if (errorLine - 1 < parts.length) {
          parts[errorLine - 1] = `<span class="sann-live-errline">${parts[errorLine - 1] || " "}</span>`;
        }
        html = parts.join("\n");
      }
      this.layer.innerHTML = html + "\n";
      this.editor.rows = Math.max(3, lines.length + 1);
      if (!errorLine) {
        if (text === this.meta.shipped) window.localStorage.removeItem(this.key);
        else window.localStorage.setItem(this.key, text);
        this.stepping = false;
      }
    }

    reset() {
      window.localStorage.removeItem(this.key);
      this.editor.value = this.meta.shipped;
      this.editorWrap.hidden = true;
      this.block.hidden = false;
      this.stepping = false;
      this.output.hidden = true;
      this.stepView.hidden = true;
      this.note("");
    }

    note(text) {
      this.status.textContent = text;
    }

    body(extra) {
      const before = (this.meta.before || []).map((i) => cells[i] ? cells[i].text() : "");
      return Object.assign({
        cell: this.meta.index, text: this.text(), file: this.meta.file || null,
        shipped: this.meta.shipped, preload: this.meta.preload || [], before,
        exercise: this.meta.exercise || null, input: this.meta.input || [],
        trace: Number(this.trace.value),
        decisions: Math.max(1, Number(this.limit.value) || DEFAULT_DECISIONS),
      }, extra || {});
    }

    servable() {
      if (window.location.protocol === "file:") {
        this.showText("This page was opened from disk, where a browser runs no Web Worker. " +
                      "Serve the book (make serve, or python -m http.server -d book/_build/html) " +
                      "and open it from http://127.0.0.1 to run the cells.", "sann-live-error");
        return false;
      }
      return true;
    }

    busy(on, what) {
      for (const b of this.root.querySelectorAll("button")) b.disabled = on;
      this.stopButton.disabled = !on;
      this.root.classList.toggle("sann-live-busy", on);
      if (on) {
        this.started = performance.now();
        this.note(worker ? `${what}…` : `${what}: starting Python in the page (a few seconds the first time)…`);
      }
    }

    /** Say in the output that Stop ended this cell's request, and how long it had run. */
    showStopped(what) {
      const seconds = ((performance.now() - this.started) / 1000).toFixed(1);
      this.showText(`Stopped after ${seconds} s: ${what} did not finish. The page's Python ` +
                    "worker was terminated, with the agents of every cell of this page; the " +
                    "next Run starts a new worker.", "sann-live-stopped");
      this.note("stopped");
      this.root.dataset.stops = String(Number(this.root.dataset.stops || 0) + 1);
    }

    async run() {
      if (!this.servable()) return;
      this.busy(true, "running");
      try {
        const answer = await request("run", this.body());
        this.stepping = false;
        this.stepView.hidden = true;
        this.showRun(answer);
      } catch (error) {
        if (error instanceof Stopped) {
          this.showStopped("the run");
        } else {
          this.showText(`The page could not run the cell: ${error.message}`, "sann-live-error");
          this.note("");
        }
      } finally {
        this.busy(false);
      }
    }

    showText(text, className) {
      this.output.hidden = false;
      const pre = element("pre", className || "sann-live-text", text);
      this.output.replaceChildren(pre);
    }

    showRun(answer) {
      this.output.hidden = false;
      this.output.replaceChildren();
      if (answer.error) {
        this.showError(answer.error);
      } else {
        this.output.appendChild(element("pre", "sann-live-text", answer.output.replace(/^\n+/, "")));
        if (answer.limit) {
          this.output.appendChild(element("p", "sann-live-limit-note",
            `Stopped at the decision limit (${this.body().decisions}): the rules did not halt. ` +
            "Runaway rules keep proposing operators or stacking impasses; raise the limit or fix the rules."));
        }
        const s = answer.stats;
        this.output.appendChild(element("p", "sann-live-stats",
          `${s.decisions} decisions · ${s.elaboration_cycles} elaboration cycles · ` +
          `${s.production_firings} production firings · WM ${s.wm_size} WMEs (max ${s.wm_max}) · ` +
          `${answer.halted ? "halted" : "not halted"}`));
        for (const q of answer.queries || []) this.showQuery(q);
      }
      if (answer.check) this.showCheck(answer.check);
      const time = `${(answer.ms / 1000).toFixed(2)} s`;
      this.note(answer.bootMs ? `ran in ${time} (Python started in ${(answer.bootMs / 1000).toFixed(1)} s)` : `ran in ${time}`);
      this.root.dataset.runs = String(Number(this.root.dataset.runs || 0) + 1);
    }

    showError(error) {
      const box = element("div", "sann-live-error");
      let where = "";
      if (error.cell_line) where = `line ${error.cell_line} of this cell, column ${error.column}: `;
      else if (error.line) where = `in ${error.file}, line ${error.line}, column ${error.column}: `;
      box.appendChild(element("p", "sann-live-error-where", `${error.kind}: ${where}`));
      box.appendChild(element("pre", "sann-live-text", error.message));
      this.output.appendChild(box);
      if (error.cell_line) {
        this.openEditor();
        this.edited(error.cell_line);
        const lines = this.editor.value.split("\n");
        const line = Math.min(Math.max(error.cell_line, 1), lines.length);
        let offset = 0;
        for (let i = 0; i < line - 1; i++) offset += lines[i].length + 1;
        offset += Math.min(error.column - 1, lines[line - 1].length);
        this.editor.focus();
        this.editor.setSelectionRange(offset, offset + 1);
      }
    }

    showCheck(check) {
      const box = element("div", "sann-live-check");
      box.dataset.passed = String(check.passed);
      box.appendChild(element("p", "sann-live-verdict",
        check.passed ? "Check: passes — every criterion holds." : "Check: not yet — see what does not hold below."));
      const list = element("ul", "");
      for (const r of check.results) {
        const item = element("li", r.passed ? "sann-live-pass" : "sann-live-fail",
                             `${r.passed ? "✔" : "✘"} ${r.name} — ${r.detail}`);
        list.appendChild(item);
      }
      box.appendChild(list);
      this.output.appendChild(box);
    }

    showQuery(q) {
      this.output.appendChild(element("p", "sann-live-query-head", q.command));
      this.output.appendChild(element("pre", "sann-live-text sann-live-query", q.text.replace(/^\n+/, "")));
    }

    async query(command) {
      if (!this.servable()) return;
      this.busy(true, command);
      try {
        const answer = await request("query", this.body({ command }));
        this.output.hidden = false;
        this.showQuery(answer);
        this.note("");
      } catch (error) {
        if (error instanceof Stopped) this.showStopped(command);
        else this.showText(`The page could not ask the agent: ${error.message}`, "sann-live-error");
      } finally {
        this.busy(false);
      }
    }

    async step(unit) {
      if (!this.servable()) return;
      this.busy(true, `stepping one ${unit}`);
      try {
        const restart = !this.stepping;
        const answer = await request("step", this.body({ unit, restart }));
        if (answer.error) {
          this.output.hidden = false;
          this.output.replaceChildren();
          this.showError(answer.error);
          this.note("");
          return;
        }
        if (restart) this.previousTags = null;
        this.stepping = true;
        this.showStep(answer);
        this.note(`${unit} stepped in ${(answer.ms / 1000).toFixed(2)} s`);
      } catch (error) {
        if (error instanceof Stopped) {
          this.stepView.hidden = true;
          this.showStopped(`the ${unit} step`);
        } else {
          this.showText(`The page could not step the cell: ${error.message}`, "sann-live-error");
        }
      } finally {
        this.busy(false);
      }
    }

    showStep(answer) {
      const view = this.stepView;
      view.hidden = false;
      view.replaceChildren();
      view.appendChild(element("p", "sann-live-phase",
        `Decision ${answer.decisions}; next phase: ${answer.phase}${answer.halted ? " (halted)" : ""}`));
      const goals = element("div", "sann-live-goals");
      for (const goal of answer.goals) {
        const g = element("div", "sann-live-goal");
        let head = `${goal.id}: `;
        head += goal.impasse ? `${goal.impasse} impasse on ^${goal.attribute}; ` : "";
        head += goal.operator ? `operator ${goal.operator} (${goal.operator_name || "?"}) selected` : "no operator selected";
        if (goal.proposed.length) head += `; proposed: ${goal.proposed.join(", ")}`;
        g.appendChild(element("p", "sann-live-goal-head", head));
        const details = element("details", "sann-live-prefs");
        details.appendChild(element("summary", "", "the preferences for its operator"));
        details.appendChild(element("pre", "sann-live-text", goal.preferences.replace(/^\n+/, "")));
        g.appendChild(details);
        goals.appendChild(g);
      }
      view.appendChild(goals);
      const graph = element("div", "sann-live-wm");
      view.appendChild(graph);
      this.previousTags = window.SannLive.drawGraph(graph, answer.graph, this.previousTags);
      graph.dataset.wmes = String(answer.graph.edges.length);
      if (answer.output && answer.output.trim()) {
        this.output.hidden = false;
        let pre = this.output.querySelector("pre.sann-live-steptrace");
        if (!pre) {
          this.output.replaceChildren();
          pre = element("pre", "sann-live-text sann-live-steptrace", "");
          this.output.appendChild(pre);
        }
        pre.textContent += answer.output;
      }
    }
  }

  function start() {
    for (const meta of document.querySelectorAll("div.sann-live-meta")) {
      const block = meta.nextElementSibling;
      if (!block) continue;
      const data = JSON.parse(meta.dataset.live);
      cells[data.index] = new LiveCell(data, block);
    }
  }

  window.SannLive = window.SannLive || {};
  window.SannLive.cells = cells;
  window.SannLive.request = request;  // for benchmarks/live.py
  if (document.readyState === "loading") document.addEventListener("DOMContentLoaded", start);
  else start();
})();
