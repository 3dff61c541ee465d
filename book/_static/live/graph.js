// Working memory as an SVG graph for the live cells' stepping view: identifiers are boxes,
// constants plain labels, each WME an arrow labelled with its attribute. Nodes are laid out in
// columns by their distance from the top state (sann.live.wm_graph computes it); WMEs that are
// new since the previous step are drawn in the accent colour.
(function () {
  "use strict";
  const SVG = "http://www.w3.org/2000/svg";
  const COLUMN = 190, ROW = 24, PAD = 16;

  function el(name, attrs, text) {
    const node = document.createElementNS(SVG, name);
    for (const [k, v] of Object.entries(attrs)) node.setAttribute(k, v);
    if (text !== undefined) node.textContent = text;
    return node;
  }

  function layout(graph) {
    const columns = [];
    const place = new Map();
    for (const node of graph.nodes) {
      const column = (columns[node.depth] ??= []);
      place.set(node.id, { x: PAD + node.depth * COLUMN, y: PAD + column.length * ROW, node });
      column.push(node);
    }
    const rows = Math.max(1, ...columns.map((c) => (c ? c.length : 0)));
    return { place, width: PAD * 2 + columns.length * COLUMN, height: PAD * 2 + rows * ROW };
  }

  /** Draw `graph` into `container`; `previous` is the set of timetags drawn last time. */
  function draw(container, graph, previous) {
    const { place, width, height } = layout(graph);
    const svg = el("svg", { class: "sann-live-graph", width, height,
                            viewBox: `0 0 ${width} ${height}`, role: "img" });
    svg.appendChild(el("title", {}, `working memory: ${graph.nodes.length} nodes`));
    const defs = el("defs", {});
    const marker = el("marker", { id: "sann-arrow", viewBox: "0 0 8 8", refX: 8, refY: 4,
                                  markerWidth: 6, markerHeight: 6, orient: "auto" });
    marker.appendChild(el("path", { d: "M0,0 L8,4 L0,8 z", fill: "#777" }));
    defs.appendChild(marker);
    svg.appendChild(defs);
    const shown = new Set();
    const labels = new Map();
    for (const edge of graph.edges) {
      const a = place.get(edge.from), b = place.get(edge.to);
      if (!a || !b) continue;
      shown.add(edge.timetag);
      const fresh = previous && !previous.has(edge.timetag);
      const x1 = a.x + 52, y1 = a.y + 8, x2 = b.x - 2, y2 = b.y + 8;
      const path = b.x > a.x
        ? `M${x1},${y1} C${x1 + 50},${y1} ${x2 - 50},${y2} ${x2},${y2}`
        : `M${x1},${y1} C${x1 + 60},${y1 - 30} ${x2 + 60},${y2 - 30} ${x2 + 52},${y2}`;
      const cls = `sann-live-edge${fresh ? " sann-live-new" : ""}${edge.acceptable ? " sann-live-acceptable" : ""}`;
      const group = el("g", { class: cls, "data-timetag": edge.timetag });
      group.appendChild(el("path", { d: path, fill: "none", "marker-end": "url(#sann-arrow)" }));
      // One label for the WMEs of one id, attribute and value: the selected operator and
      // its acceptable preference (S1 ^operator O1 and S1 ^operator O1 +) share their arrow.
      const key = `${edge.from} ${edge.attr} ${edge.to}`;
      const label = labels.get(key);
      if (label) {
        label.textContent = `^${edge.attr} (and +)`;
      } else {
        const text = el("text", { x: x2 - 6, y: y2 - 3, "text-anchor": "end" },
                        `^${edge.attr}${edge.acceptable ? " +" : ""}`);
        labels.set(key, text);
        group.appendChild(text);
      }
      svg.appendChild(group);
    }
    for (const { x, y, node } of place.values()) {
      const group = el("g", { class: `sann-live-node sann-live-${node.kind}`, "data-id": node.id });
      if (node.kind !== "constant") {
        group.appendChild(el("rect", { x, y, width: 50, height: 16, rx: 4 }));
        group.appendChild(el("text", { x: x + 25, y: y + 12, "text-anchor": "middle" }, node.label));
      } else {
        group.appendChild(el("text", { x, y: y + 12 }, node.label.slice(0, 28)));
      }
      svg.appendChild(group);
    }
    container.replaceChildren(svg);
    if (graph.cut) {
      const note = document.createElement("p");
      note.textContent = `Working memory has ${graph.wm_size} WMEs: the graph shows the first ${graph.nodes.length} nodes.`;
      container.appendChild(note);
    }
    return shown;
  }

  window.SannLive = window.SannLive || {};
  window.SannLive.drawGraph = draw;
})();
