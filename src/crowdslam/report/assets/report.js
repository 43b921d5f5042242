// crowdslam report page: draws the embedded run data (the report-data JSON block) with Chart.js.
// Every chart is a Chart.js chart; this script only lays them out. After drawing, <body> gets
// data-charts (charts drawn) and data-charts-expected; data-errors counts JavaScript errors.
(function () {
  'use strict';
  var data = JSON.parse(document.getElementById('report-data').textContent);
  var runs = data.runs;
  var palette = ['#1f77b4', '#d62728', '#2ca02c', '#ff7f0e', '#9467bd', '#8c564b', '#e377c2', '#17becf'];
  var axisNames = ['x', 'y', 'z'];
  var main = document.getElementById('report');
  var drawn = 0;
  var lastTime = 0;  // of any run's last frame: the time axes end there
  runs.forEach(function (run) {
    if (run.frames.t.length > 0) lastTime = Math.max(lastTime, run.frames.t[run.frames.t.length - 1]);
  });
  var expected = 0;

  Chart.defaults.animation = false;
  Chart.defaults.maintainAspectRatio = false;
  Chart.defaults.font.size = 12;
  Chart.defaults.plugins.legend.labels.boxWidth = 12;

  function colour(k) { return palette[k % palette.length]; }
  // Series j of run k: with one run each series has its own colour; with several, the run's colour
  // (series then differ by line style).
  var seriesPalette = ['#1f77b4', '#ff7f0e', '#2ca02c', '#9467bd'];
  function seriesColour(k, j) { return runs.length === 1 ? seriesPalette[j % seriesPalette.length] : colour(k); }

  function faded(hex, opacity) {
    var v = parseInt(hex.slice(1), 16);
    return 'rgba(' + ((v >> 16) & 255) + ',' + ((v >> 8) & 255) + ',' + (v & 255) + ',' + opacity + ')';
  }

  function element(tag, attributes, parent, text) {
    var node = document.createElement(tag);
    Object.keys(attributes || {}).forEach(function (key) { node.setAttribute(key, attributes[key]); });
    if (text !== undefined) node.textContent = text;
    if (parent) parent.appendChild(node);
    return node;
  }

  function section(title, id, note) {
    var node = element('section', { id: id }, main);
    element('h2', {}, node, title);
    if (note) element('p', { class: 'note' }, node, note);
    return node;
  }

  function countError() {
    document.body.dataset.errors = String(Number(document.body.dataset.errors || 0) + 1);
  }

  // One chart in its own box; a chart that fails is counted as an error and the others are still drawn.
  function addChart(parent, sizeClass, config) {
    expected += 1;
    var box = element('div', { class: 'chart ' + (sizeClass || '') }, parent);
    var canvas = element('canvas', {}, box);
    try {
      new Chart(canvas, config);
      drawn += 1;
    } catch (e) {
      countError();
      element('p', { class: 'note' }, box, 'chart failed: ' + e);
    }
  }

  function points(xs, ys, scale) {
    var out = new Array(xs.length);
    for (var i = 0; i < xs.length; i++) out[i] = { x: xs[i], y: scale ? ys[i] * scale : ys[i] };
    return out;
  }

  // Several datasets of one run share a label (map segments): the legend shows it once.
  function legend() {
    return {
      labels: {
        filter: function (item, chartData) {
          for (var i = 0; i < item.datasetIndex; i++) {
            if (chartData.datasets[i].label === item.text) return false;
          }
          return true;
        }
      }
    };
  }

  function timeAxis() {
    return axis('time (s)', { min: 0, max: Math.max(lastTime, 0.001), ticks: { includeBounds: false } });
  }
  function title(text) { return { display: true, text: text }; }
  function axis(text, extra) {
    var a = { type: 'linear', title: { display: true, text: text } };
    Object.keys(extra || {}).forEach(function (key) { a[key] = extra[key]; });
    return a;
  }
  function line(label, pts, k, extra) {
    var d = { label: label, data: pts, borderColor: colour(k), backgroundColor: colour(k), borderWidth: 1.5,
              pointRadius: 0, showLine: true, fill: false };
    Object.keys(extra || {}).forEach(function (key) { d[key] = extra[key]; });
    return d;
  }

  // ---- summary -------------------------------------------------------------------------------
  function drawSummary() {
    document.getElementById('title').textContent = data.title;
    var datasets = [];
    runs.forEach(function (run) { if (datasets.indexOf(run.dataset) < 0) datasets.push(run.dataset); });
    document.getElementById('subtitle').textContent =
        'dataset ' + datasets.join(', ') + ' \u00b7 generated ' + data.generated + ' by crowdslam report';
    var table = document.getElementById('summary-table');
    var head = element('tr', {}, element('thead', {}, table));
    element('th', {}, head, '');
    runs.forEach(function (run, k) {
      var th = element('th', { title: run.dir }, head);
      element('span', { class: 'swatch', style: 'background:' + colour(k) }, th);
      th.appendChild(document.createTextNode(run.label));
    });
    var body = element('tbody', {}, table);
    data.summary_rows.forEach(function (row, i) {
      var tr = element('tr', {}, body);
      element('th', {}, tr, row);
      runs.forEach(function (run) { element('td', {}, tr, run.summary[i]); });
    });
    var summary = document.getElementById('summary');
    runs.forEach(function (run) {
      if (run.ground_truth_note) element('p', { class: 'note' }, summary, run.label + ': ' + run.ground_truth_note);
      if (run.keyframes_note) element('p', { class: 'note' }, summary, run.label + ': keyframes not shown: ' + run.keyframes_note);
    });
  }

  // ---- trajectories --------------------------------------------------------------------------
  function trajectoryConfig(view, heading) {
    var a = axisNames[view[0]], b = axisNames[view[1]];
    var datasets = [];
    var groundTruthShown = {};
    runs.forEach(function (run, k) {
      if (run.ground_truth && !groundTruthShown[run.dataset]) {
        groundTruthShown[run.dataset] = true;
        datasets.push(line(Object.keys(groundTruthShown).length > 1 ? 'ground truth (' + run.label + ')' : 'ground truth',
                           points(run.ground_truth[a], run.ground_truth[b]), 0,
                           { borderColor: '#555', backgroundColor: '#555', borderWidth: 2.5, borderDash: [6, 3] }));
      }
      run.segments.forEach(function (s) {
        var label = run.label + (s.aligned ? '' : ' (not aligned)');
        datasets.push(line(label, points(s.poses[a], s.poses[b]), k));
        if (s.keyframes.t.length > 0) {
          datasets.push(line(run.label + ' keyframes', points(s.keyframes[a], s.keyframes[b]), k,
                             { showLine: false, pointRadius: 2.5, backgroundColor: faded(colour(k), 0.6) }));
        }
      });
    });
    // The same metres per unit on both axes (the box is nearly square).
    var lo = [Infinity, Infinity], hi = [-Infinity, -Infinity];
    datasets.forEach(function (d) {
      d.data.forEach(function (p) {
        lo[0] = Math.min(lo[0], p.x); hi[0] = Math.max(hi[0], p.x);
        lo[1] = Math.min(lo[1], p.y); hi[1] = Math.max(hi[1], p.y);
      });
    });
    var ticks = { includeBounds: false };  // nice round ticks only, none at the (computed) edges
    var x = axis(a + ' (m)', { ticks: ticks }), y = axis(b + ' (m)', { ticks: ticks });
    if (isFinite(lo[0])) {
      var half = Math.max(hi[0] - lo[0], hi[1] - lo[1], 0.01) * 0.55;
      var cx = (lo[0] + hi[0]) / 2, cy = (lo[1] + hi[1]) / 2;
      x.min = cx - half; x.max = cx + half; y.min = cy - half; y.max = cy + half;
    }
    return { type: 'scatter', data: { datasets: datasets },
             options: { scales: { x: x, y: y }, plugins: { title: title(heading), legend: legend() } } };
  }

  function drawTrajectories() {
    var aligned = runs.filter(function (run) { return run.alignment !== 'none'; }).map(function (run) {
      var evaluated = run.evaluated_segment !== null ? run.segments[run.evaluated_segment] : null;
      var scale = run.alignment === 'sim3' && evaluated && evaluated.errors
          ? ', scale ' + evaluated.errors.scale.toPrecision(4) : '';
      return run.label + ': ' + run.alignment + scale;
    });
    var note = aligned.length > 0
        ? 'Estimated trajectory aligned to the ground truth as the ATE is (' + aligned.join(', ') + '; each map segment on its own).'
        : 'No ground truth: the trajectories are shown in their own frame.';
    var node = section('Trajectory', 'trajectory', note);
    var pair = element('div', { class: 'pair' }, node);
    var top = data.axes.top, side = data.axes.side;
    addChart(element('div', {}, pair), 'square',
             trajectoryConfig(top, 'from above (' + axisNames[top[0]] + '-' + axisNames[top[1]] + ')'));
    addChart(element('div', {}, pair), 'square',
             trajectoryConfig(side, 'from the side (' + axisNames[side[0]] + '-' + axisNames[side[1]] + ')'));
  }

  function drawErrors() {
    var datasets = [];
    runs.forEach(function (run, k) {
      run.segments.forEach(function (s) {
        if (s.errors) datasets.push(line(run.label, points(s.errors.t, s.errors.e), k));
      });
    });
    if (datasets.length === 0) {
      section('Translation error over time', 'errors', 'No run could be evaluated against a ground truth.');
      return;
    }
    var node = section('Translation error over time', 'errors',
                       'Distance between each aligned pose and its ground-truth pose (the ATE is the RMS of these).');
    addChart(node, '', { type: 'line', data: { datasets: datasets },
                         options: { scales: { x: timeAxis(), y: axis('translation error (m)', { beginAtZero: true }) },
                                    plugins: { legend: legend() } } });
  }

  // ---- time --------------------------------------------------------------------------------
  function drawFrameTimes() {
    var node = section('Time per frame', 'frame-time',
                       'Stacked by stage: ORB extraction, waiting for the people detector, tracking (which includes any wait for local mapping).');
    var datasets = [];
    runs.forEach(function (run, k) {
      var f = run.frames;
      var single = runs.length === 1;
      var stages = [['extraction', f.extraction_ms, single ? 0.6 : 0.75], ['detector wait', f.detector_wait_ms, single ? 0.6 : 0.45],
                    ['tracking', f.tracking_ms, single ? 0.6 : 0.2]];
      stages.forEach(function (stage, j) {
        datasets.push(line(run.label + ': ' + stage[0], points(f.t, stage[1]), k,
                           { stack: run.label, fill: j === 0 ? 'origin' : '-1', borderWidth: 0.6,
                             borderColor: seriesColour(k, j), backgroundColor: faded(seriesColour(k, j), stage[2]) }));
      });
    });
    addChart(node, 'tall', { type: 'line', data: { datasets: datasets },
                             options: { scales: { x: timeAxis(), y: axis('ms', { stacked: true, beginAtZero: true }) } } });
  }

  function drawMapping() {
    var withMapping = runs.filter(function (run) { return run.mapping; });
    if (withMapping.length === 0) {
      section('Local mapping per keyframe', 'mapping', 'The runs recorded no local mapping statistics.');
      return;
    }
    var node = section('Local mapping per keyframe', 'mapping',
                       'Median and 95th percentile over the keyframes of each mapping step, then each keyframe\'s time stacked by step, in the order the mapper processed them.');
    var datasets = [];
    runs.forEach(function (run, k) {
      if (!run.mapping) return;
      datasets.push({ label: run.label + ': median', data: run.mapping.median, backgroundColor: colour(k) });
      datasets.push({ label: run.label + ': p95', data: run.mapping.p95, backgroundColor: faded(colour(k), 0.4) });
    });
    addChart(node, '', { type: 'bar', data: { labels: withMapping[0].mapping.steps, datasets: datasets },
                         options: { scales: { y: { beginAtZero: true, title: { display: true, text: 'ms per keyframe' } } } } });
    drawMappingPerKeyframe(node, withMapping.filter(function (run) { return run.mapping.keyframes; }));
  }

  // Each keyframe's mapping time, stacked by step (the rest of the total: removing bad points, the
  // keyframe database); one stack per run.
  function drawMappingPerKeyframe(node, withTimes) {
    if (withTimes.length === 0) {
      element('p', { class: 'note' }, node, 'No per-keyframe times (run.json written before they were recorded).');
      return;
    }
    var steps = ['register', 'triangulation', 'fusion', 'local_ba', 'culling'];
    var datasets = [];
    runs.forEach(function (run, k) {
      if (withTimes.indexOf(run) < 0) return;
      var kf = run.mapping.keyframes;
      var rest = kf.total.map(function (total, i) {
        return Math.max(0, total - steps.reduce(function (sum, step) { return sum + kf[step][i]; }, 0));
      });
      steps.map(function (step) { return [step, kf[step]]; }).concat([['other', rest]]).forEach(function (series, j) {
        var c = runs.length === 1 ? palette[j % palette.length] : colour(k);
        var opacity = runs.length === 1 ? 0.6 : 0.15 + 0.12 * j;
        datasets.push(line(run.label + ': ' + series[0], points(kf.n, series[1]), k,
                           { stack: run.label, fill: j === 0 ? 'origin' : '-1', borderWidth: 0.6,
                             borderColor: c, backgroundColor: faded(c, opacity) }));
      });
    });
    addChart(node, 'tall', { type: 'line', data: { datasets: datasets },
                             options: { scales: { x: axis('keyframe (in processing order)', { ticks: { precision: 0 } }),
                                                  y: axis('ms', { stacked: true, beginAtZero: true }) } } });
  }

  // ---- people filter -------------------------------------------------------------------------
  function drawPeople() {
    var node = section('People', 'people', 'Share of the image covered by person boxes, and the boxes per frame.');
    var datasets = [];
    runs.forEach(function (run, k) {
      var f = run.frames;
      datasets.push(line(run.label + ': people coverage', points(f.t, f.people_area, 100), k,
                         { yAxisID: 'y', borderColor: seriesColour(k, 0), backgroundColor: seriesColour(k, 0) }));
      datasets.push(line(run.label + ': person boxes', points(f.t, f.person_boxes), k,
                         { yAxisID: 'boxes', borderDash: [4, 3], borderWidth: 1, borderColor: seriesColour(k, 1),
                           backgroundColor: seriesColour(k, 1) }));
    });
    addChart(node, '', { type: 'line', data: { datasets: datasets },
                         options: { scales: { x: timeAxis(), y: axis('covered by people (%)', { beginAtZero: true }),
                                              boxes: axis('person boxes', { position: 'right', beginAtZero: true,
                                                                            grid: { drawOnChartArea: false } }) } } });
  }

  function drawFeatures() {
    var node = section('Features', 'features',
                       'Feature budget (grows with the area the people filter removes), keypoints kept and removed by the filter.');
    var datasets = [];
    runs.forEach(function (run, k) {
      var f = run.frames;
      var removed = f.keypoints_before_filter.map(function (before, i) { return before - f.keypoints[i]; });
      var style = function (j, extra) {
        var c = runs.length === 1 ? seriesColour(k, j) : faded(colour(k), [1, 1, 0.55][j]);
        var d = { borderColor: c, backgroundColor: c };
        Object.keys(extra).forEach(function (key) { d[key] = extra[key]; });
        return d;
      };
      datasets.push(line(run.label + ': feature budget', points(f.t, f.feature_budget), k, style(0, { borderWidth: 2 })));
      datasets.push(line(run.label + ': keypoints kept', points(f.t, f.keypoints), k,
                         style(1, { borderWidth: 1, borderDash: runs.length === 1 ? [] : [5, 2] })));
      datasets.push(line(run.label + ': keypoints removed', points(f.t, removed), k, style(2, { borderWidth: 1 })));
    });
    addChart(node, '', { type: 'line', data: { datasets: datasets },
                         options: { scales: { x: timeAxis(), y: axis('keypoints', { beginAtZero: true }) } } });
  }

  // ---- tracking timeline -----------------------------------------------------------------------
  var rows = ['not initialised', 'lost / bridged', 'relocalisation', 'reference keyframe', 'motion model', 'initialisation',
              'keyframe', 'loop closed', 'map reset'];
  function rowOf(state, method) {
    if (method === 'init') return 5;
    if (method === 'motion') return 4;
    if (method === 'reference') return 3;
    if (method === 'relocalization') return 2;
    if (state === 'not_initialized') return 0;
    return 1;
  }

  function drawTimeline() {
    var node = section('Tracking', 'tracking',
                       'How each frame was tracked; relocalisations, keyframes, loops closed and map resets marked.');
    var datasets = [];
    runs.forEach(function (run, k) {
      var f = run.frames;
      var offset = runs.length > 1 ? (k - (runs.length - 1) / 2) * 0.18 : 0;
      var tracked = [], relocalised = [], keyframes = [];
      for (var i = 0; i < f.t.length; i++) {
        var row = rowOf(f.state[i], f.method[i]);
        tracked.push({ x: f.t[i], y: row + offset });
        if (row === 2) relocalised.push({ x: f.t[i], y: row + offset });
        if (f.keyframe[i]) keyframes.push({ x: f.t[i], y: 6 + offset });
      }
      var at = function (events, row) { return events.map(function (e) { return { x: e.t, y: row + offset }; }); };
      datasets.push(line(run.label + ': method', tracked, k, { showLine: false, pointRadius: 1.5 }));
      datasets.push(line(run.label + ': relocalisations', relocalised, k, { showLine: false, pointRadius: 6, pointStyle: 'triangle' }));
      datasets.push(line(run.label + ': keyframes', keyframes, k, { showLine: false, pointRadius: 2.5, pointStyle: 'rect' }));
      datasets.push(line(run.label + ': loops', at(run.loops, 7), k, { showLine: false, pointRadius: 9, pointStyle: 'star', borderWidth: 2 }));
      datasets.push(line(run.label + ': map resets', at(run.resets, 8), k, { showLine: false, pointRadius: 9, pointStyle: 'crossRot', borderWidth: 2 }));
    });
    addChart(node, 'tall', {
      type: 'scatter', data: { datasets: datasets },
      options: { scales: { x: timeAxis(),
                           y: { type: 'linear', min: -0.5, max: rows.length - 0.5,
                                afterBuildTicks: function (scale) {
                                  scale.ticks = rows.map(function (row, i) { return { value: i }; });
                                },
                                ticks: { autoSkip: false, callback: function (v) { return rows[v]; } } } },
                 plugins: { legend: { labels: { usePointStyle: true } } } }
    });
  }

  // ---- saved frames --------------------------------------------------------------------------
  function drawFrames() {
    var any = runs.some(function (run) { return run.saved_frames.length > 0; });
    if (!any) {
      section('Saved frames', 'frames', 'No saved frames (run with --save-frames N to see what the people filter removed).');
      return;
    }
    runs.forEach(function (run) {
      if (run.saved_frames.length === 0) return;
      var node = section('Saved frames: ' + run.label, 'frames-' + run.label,
                         run.saved_frames.length + ' of ' + run.saved_frames_total +
                         ' saved frames: person boxes blue, keypoints kept green and removed red.');
      var strip = element('div', { class: 'strip' }, node);
      run.saved_frames.forEach(function (frame) {
        var figure = element('figure', {}, strip);
        element('img', { src: frame.src, alt: 'frame ' + frame.frame }, figure);
        element('figcaption', {}, figure, 'frame ' + frame.frame);
      });
    });
  }

  [drawSummary, drawTrajectories, drawErrors, drawFrameTimes, drawMapping, drawPeople, drawFeatures, drawTimeline,
   drawFrames].forEach(function (draw) {
    try {
      draw();
    } catch (e) {
      countError();
      element('p', { class: 'note' }, main, 'part of the report failed: ' + e);
    }
  });
  document.body.dataset.chartsExpected = String(expected);
  document.body.dataset.charts = String(drawn);
})();
