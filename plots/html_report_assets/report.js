// contactbench's HTML report (plots/html_report.py): the runs table, the convergence histories and
// the performance profiles, drawn with d3 v3 (Debian's libjs-d3, copied beside the page) from the
// JSON embedded in the page. Every string of a record reaches the page through .text() (the DOM's
// textContent), never as markup.
(function () {
  "use strict";
  var data = JSON.parse(document.getElementById("report-data").textContent);
  var sci = d3.format(".3g");
  var expFormat = d3.format(".0e");

  function fmtNumber(v, digits) {
    if (v === null || v === undefined) return "\u2014";
    if (v !== 0 && (Math.abs(v) < 1e-3 || Math.abs(v) >= 1e5)) return v.toExponential(digits - 1);
    if (Math.round(v) === v && Math.abs(v) < 1e9) return String(v);
    return sci(v);
  }

  // ---- the runs table ----------------------------------------------------------------------
  var multiSet = data.sets.length > 1;
  var columns = [
    {key: "set", title: "suite", text: true, show: multiSet},
    {key: "snapshot", title: "snapshot", text: true},
    {key: "label", title: "label", text: true},
    {key: "solver", title: "solver", text: true},
    {key: "status", title: "status", text: true},
    {key: "e", title: "e (original QP)", digits: 3},
    {key: "tol", title: "tol", digits: 2},
    {key: "time_s", title: "time [s] (setup + solve)", digits: 3},
    {key: "setup_s", title: "setup [s]", digits: 3},
    {key: "iterations", title: "iterations", digits: 6},
    {key: "peak_mb", title: "peak memory [MiB]", digits: 4},
    {key: "n", title: "n", digits: 9},
    {key: "m", title: "m", digits: 9},
    {key: "message", title: "message", text: true}
  ].filter(function (c) { return c.show !== false; });

  var sortKey = null, sortDir = 1;
  var table = d3.select("#runs-table");
  table.select("thead").append("tr").selectAll("th").data(columns).enter().append("th")
    .attr("data-key", function (c) { return c.key; })
    .text(function (c) { return c.title; })
    .on("click", function (c) {
      sortDir = sortKey === c.key ? -sortDir : 1;
      sortKey = c.key;
      table.selectAll("th").attr("class", function (d) {
        return d.key === sortKey ? (sortDir > 0 ? "sorted-asc" : "sorted-desc") : null;
      });
      drawRows();
    });

  function compare(a, b) {
    var x = a[sortKey], y = b[sortKey];
    var xn = x === null || x === undefined || x === "", yn = y === null || y === undefined || y === "";
    if (xn || yn) return xn === yn ? 0 : (xn ? 1 : -1);  // missing values last, either direction
    if (typeof x === "number" && typeof y === "number") return sortDir * (x - y);
    return sortDir * String(x).localeCompare(String(y));
  }

  function cellText(row, c) {
    return c.text ? String(row[c.key] === null || row[c.key] === undefined ? "" : row[c.key])
                  : fmtNumber(row[c.key], c.digits);
  }

  function drawRows() {
    var needle = document.getElementById("filter").value.toLowerCase();
    var rows = data.rows.filter(function (r) {
      if (!needle) return true;
      return columns.some(function (c) { return cellText(r, c).toLowerCase().indexOf(needle) >= 0; });
    });
    if (sortKey) rows = rows.slice().sort(compare);
    var tr = table.select("tbody").selectAll("tr").data(rows);
    tr.enter().append("tr");
    tr.exit().remove();
    tr.attr("class", function (r) { return r.status === "converged" ? null : "failed"; });
    var td = tr.selectAll("td").data(function (r) { return columns.map(function (c) { return [r, c]; }); });
    td.enter().append("td");
    td.attr("class", function (d) { return d[1].text ? (d[1].key === "status" ? "status" : null) : "num"; })
      .text(function (d) { return cellText(d[0], d[1]); });
    d3.select("#count").text(rows.length + " of " + data.rows.length + " runs");
  }
  d3.select("#filter").on("input", drawRows);
  drawRows();

  // ---- charts ------------------------------------------------------------------------------
  var M = {top: 8, right: 150, bottom: 42, left: 62}, W = 330, H = 230;

  // One chart: log or linear axes with their labels, one path per series, an x on failed final
  // points, the horizontal reference line labelled, and a clickable legend.
  function chart(parent, o) {
    var box = parent.append("div").attr("class", "plot");
    box.append("h3").text(o.title);
    var svg = box.append("svg").attr("width", W + M.left + M.right).attr("height", H + M.top + M.bottom);
    var g = svg.append("g").attr("transform", "translate(" + M.left + "," + M.top + ")");
    var xs = [], ys = [];
    o.series.forEach(function (s) {
      s.pts.forEach(function (p) { xs.push(p[0]); ys.push(p[1]); });
    });
    if (o.hline) ys.push(o.hline.y);
    var xd = d3.extent(xs), yd = d3.extent(ys);
    if (xd[0] === undefined) { xd = o.xlog ? [1e-3, 1] : [0, 1]; }
    if (yd[0] === undefined) { yd = [1e-8, 1]; }
    if (xd[0] === xd[1]) xd = o.xlog ? [xd[0] / 2, xd[0] * 2] : [xd[0] - 1, xd[0] + 1];
    if (yd[0] === yd[1]) yd = o.ylog ? [yd[0] / 10, yd[0] * 10] : [yd[0] - 1, yd[0] + 1];
    if (o.xlog) xd = [xd[0] / 1.3, xd[1] * 1.3]; else xd = [Math.min(0, xd[0]), xd[1] * 1.05];
    if (o.ylog) yd = [yd[0] / 3, yd[1] * 3]; else yd = [0, Math.max(1, yd[1]) * 1.02];
    var x = (o.xlog ? d3.scale.log().base(o.xbase || 10) : d3.scale.linear()).domain(xd).range([0, W]);
    var y = (o.ylog ? d3.scale.log() : d3.scale.linear()).domain(yd).range([H, 0]);
    var xAxis = d3.svg.axis().scale(x).orient("bottom").ticks(5);
    if (o.xlog && o.xbase === 2) xAxis.tickFormat(d3.format("g"));
    else if (o.xlog) xAxis.tickValues(decades(xd, 5)).tickFormat(expFormat);
    var yAxis = d3.svg.axis().scale(y).orient("left").ticks(5);
    if (o.ylog) yAxis.tickValues(decades(yd, 8)).tickFormat(expFormat); else yAxis.tickFormat(d3.format(".1f"));
    g.append("g").attr("class", "axis x").attr("transform", "translate(0," + H + ")").call(xAxis);
    g.append("g").attr("class", "axis y").call(yAxis);
    g.append("text").attr("x", W / 2).attr("y", H + 36).attr("text-anchor", "middle").text(o.xlabel);
    g.append("text").attr("transform", "rotate(-90)").attr("x", -H / 2).attr("y", -48)
      .attr("text-anchor", "middle").text(o.ylabel);
    if (o.hline) {
      g.append("line").attr("class", "tol").attr("x1", 0).attr("x2", W)
        .attr("y1", y(o.hline.y)).attr("y2", y(o.hline.y));
      g.append("text").attr("x", W - 2).attr("y", y(o.hline.y) - 3).attr("text-anchor", "end")
        .style("font-size", "11px").text(o.hline.label);
    }
    var line = d3.svg.line().x(function (p) { return x(p[0]); }).y(function (p) { return y(p[1]); })
      .interpolate(o.step ? "step-after" : "linear");
    var paths = [];
    o.series.forEach(function (s, i) {
      var gs = g.append("g").attr("class", "s" + i);
      var p = gs.append("path").attr("class", "series" + (s.dash ? " dashed" : "")).attr("d", line(s.pts))
        .style("stroke", s.colour);
      p.append("title").text(s.label);
      if (s.failed && s.pts.length) {
        var last = s.pts[s.pts.length - 1];
        gs.append("path").attr("d", "M-4,-4L4,4M-4,4L4,-4").style("stroke", "#000").style("stroke-width", 1.5)
          .attr("transform", "translate(" + x(last[0]) + "," + y(last[1]) + ")")
          .append("title").text(s.label + ": " + s.status);
      }
      paths.push(gs);
    });
    var legend = svg.append("g").attr("class", "legend")
      .attr("transform", "translate(" + (M.left + W + 10) + "," + M.top + ")");
    o.series.forEach(function (s, i) {
      var item = legend.append("g").attr("transform", "translate(0," + (i * 15) + ")");
      item.append("line").attr("x1", 0).attr("x2", 16).attr("y1", 5).attr("y2", 5)
        .attr("class", "series" + (s.dash ? " dashed" : "")).style("stroke", s.colour);
      item.append("text").attr("x", 20).attr("y", 9).text(s.label.length > 20 ? s.label.slice(0, 19) + "\u2026" : s.label)
        .append("title").text(s.label);
      item.on("click", function () {
        var off = !item.classed("off");
        item.classed("off", off);
        paths[i].style("display", off ? "none" : null);
      });
    });
    return box;
  }

  // Ticks of a log axis: whole decades inside the domain, every k-th so that at most `most` are
  // labelled (no "0" on a log axis, no crowding).
  function decades(domain, most) {
    var lo = Math.ceil(Math.log(domain[0]) / Math.LN10 - 1e-9), hi = Math.floor(Math.log(domain[1]) / Math.LN10 + 1e-9);
    var step = Math.max(1, Math.ceil((hi - lo + 1) / most)), out = [];
    for (var e = hi; e >= lo; e -= step) out.unshift(Math.pow(10, e));
    return out;
  }

  var hroot = d3.select("#history-plots");
  if (!data.histories.length) hroot.append("p").text("No runs with a history.");
  data.histories.forEach(function (h) {
    var section = hroot.append("div").attr("class", "snapshot");
    var size = [h.n !== null ? "n = " + h.n : null, h.m !== null ? "m = " + h.m : null].filter(Boolean).join(", ");
    section.append("h3").text((multiSet ? h.set + ": " : "") + h.snapshot + (size ? " (" + size + ")" : ""));
    var plots = section.append("div").attr("class", "plots");
    var hline = h.tol !== null ? {y: h.tol, label: "tol = " + fmtNumber(h.tol, 2)} : null;
    function series(xi, positiveX) {
      return h.series.map(function (s) {
        return {label: s.label, colour: s.colour, dash: s.dash, status: s.status, failed: s.status !== "converged",
                pts: s.points.filter(function (p) {
                  return p[xi] !== null && p[2] !== null && (!positiveX || p[xi] > 0);
                }).map(function (p) { return [p[xi], p[2]]; })};
      });
    }
    chart(plots, {title: "e against time", xlabel: "time [s] (setup + solve)", ylabel: "e (original QP)",
                  xlog: true, ylog: true, hline: hline, series: series(0, true)});
    chart(plots, {title: "e against iterations", xlabel: "iterations", ylabel: "e (original QP)",
                  xlog: false, ylog: true, hline: hline, series: series(1, false)});
  });

  // ---- profiles ----------------------------------------------------------------------------
  var proot = d3.select("#profile-plots");
  if (!data.profiles.length) proot.append("p").text("No profile: no run reached a judged tier.");
  data.profiles.forEach(function (p) {
    var section = proot.append("div").attr("class", "profile");
    if (p.error) { section.append("p").text(p.set + ": " + p.error); return; }
    section.append("h3").text((multiSet ? p.set + ": " : "") + p.problems + " problems; tier e <= " +
                              fmtNumber(p.tier, 2) + "; shift " + fmtNumber(p.shift_s, 2) + " s; penalty " +
                              fmtNumber(p.penalty_s, 3) + " s");
    var tauMax = 2;
    p.labels.forEach(function (l) { l.ratios.forEach(function (r) { tauMax = Math.max(tauMax, r * 1.5); }); });
    var series = p.labels.map(function (l) {
      var pts = [[1, 0]];
      l.ratios.forEach(function (r, k) { pts.push([Math.max(r, 1), (k + 1) / l.judged]); });
      pts.push([tauMax, l.ratios.length / l.judged]);
      return {label: l.label, colour: l.colour, dash: false, failed: false, pts: pts};
    });
    var plots = section.append("div").attr("class", "plots");
    chart(plots, {title: "performance profile", xlabel: "tau (time / best time, log2)",
                  ylabel: "share of problems", xlog: true, xbase: 2, ylog: false, step: true, series: series});
    var t = section.append("table").attr("class", "sgm");
    var head = t.append("thead").append("tr");
    head.append("th").text("label");
    p.tiers.forEach(function (tier) {
      head.append("th").text("e <= " + tier + ": solved");
      head.append("th").text("e <= " + tier + ": sgm [s] (ratio to best)");
    });
    p.sgm.forEach(function (row) {
      var tr = t.append("tr");
      tr.append("td").text(row.label);
      p.tiers.forEach(function (tier) {
        var c = row[tier] || {};
        tr.append("td").attr("class", "num").text(c.success === null || c.success === undefined ? "\u2014"
                                                  : Math.round(100 * c.success) + "%");
        tr.append("td").attr("class", "num").text(fmtNumber(c.sgm, 3) + " (" + fmtNumber(c.ratio, 3) + ")");
      });
    });
  });
})();
