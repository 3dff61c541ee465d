// The live book's Web Worker: Pyodide (copied from the npm package by book/live_ext.py) with
// the engine archive packed at build time from the package's sources, answering the page's
// requests through sann.live. One worker serves every cell of a page.
import { loadPyodide } from "./pyodide/pyodide.mjs";

const base = new URL("./", import.meta.url);
let ready = null;

const DISPATCH = `
import json, os, sys
os.chdir("/home/pyodide/sann-live/sann")  # where rules/ is: rule files name each other from there
sys.path.insert(0, "/home/pyodide/sann-live")
import sann.live as live

_agents = {}
_steppers = {}

def _live_dispatch(op, request_json):
    request = json.loads(request_json)
    cell = request.get("cell")
    if op == "run":
        _steppers.pop(cell, None)
        answer, agent = live.run_cell_keeping(request)
        _agents[cell] = agent
        return json.dumps(answer)
    if op == "step":
        stepper = _steppers.get(cell)
        if stepper is None or request.get("restart"):
            try:
                stepper = _steppers[cell] = live.Stepper(request)
            except live.SoarError as error:
                return json.dumps({"error": live.error_report(error, live.Cell.of(request))})
            _agents[cell] = stepper.agent
        return json.dumps(stepper.step(request.get("unit", "decision")))
    if op == "query":
        agent = _agents.get(cell)
        if agent is None:
            return json.dumps({"command": request["command"], "text": "Run the cell first."})
        return json.dumps(live.query(agent, request["command"]))
    if op == "hanoi":
        return json.dumps(live.hanoi_rate(request.get("disks")))
    raise ValueError(f"unknown request {op}")
`;

async function boot() {
  const started = performance.now();
  const pyodide = await loadPyodide({ indexURL: new URL("pyodide/", base).href });
  const archive = await fetch(new URL("sann-live.zip", base));
  if (!archive.ok) throw new Error(`sann-live.zip: HTTP ${archive.status}`);
  pyodide.unpackArchive(await archive.arrayBuffer(), "zip",
                        { extractDir: "/home/pyodide/sann-live" });
  pyodide.runPython(DISPATCH);
  return { pyodide, bootMs: performance.now() - started };
}

self.onmessage = async (event) => {
  const { id, op, request } = event.data;
  try {
    const first = ready === null;
    ready ??= boot();
    const { pyodide, bootMs } = await ready;
    const started = performance.now();
    const dispatch = pyodide.globals.get("_live_dispatch");
    const answer = JSON.parse(dispatch(op, JSON.stringify(request)));
    dispatch.destroy();
    answer.ms = performance.now() - started;
    if (first) answer.bootMs = bootMs;
    self.postMessage({ id, answer });
  } catch (error) {
    self.postMessage({ id, failure: String(error && error.message ? error.message : error) });
  }
};
