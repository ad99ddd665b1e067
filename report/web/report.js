// demcal's campaign report: turns the report document (report/report_data.hpp: the
// coordinator's own replies) into tables and Vega-Lite plots. The same script draws the static
// report.html (data inline) and the live page (data polled from the coordinator's HTTP API).
// docs/report.md says what every plot shows and which figure of seed 000 it follows.
(function () {
  'use strict';

  const page = window.DEMCAL_PAGE || { mode: 'static' };
  const state = { views: [], expected: 0, rendered: 0, failed: 0, last: '' };

  // ---- small helpers ----

  function el(tag, attrs, ...children) {
    const e = document.createElement(tag);
    for (const [k, v] of Object.entries(attrs || {})) {
      if (v === undefined || v === null) continue;
      if (k === 'class') e.className = v;
      else if (k.startsWith('data-')) e.setAttribute(k, String(v));
      else e[k] = v;
    }
    for (const c of children.flat()) {
      if (c === undefined || c === null) continue;
      e.appendChild(typeof c === 'string' || typeof c === 'number' ? document.createTextNode(String(c)) : c);
    }
    return e;
  }

  function fmt(v, digits) {
    if (v === null || v === undefined || typeof v !== 'number' || !isFinite(v)) return '-';
    return Number(v.toPrecision(digits || 5)).toString();
  }

  function pct(v) {
    return typeof v === 'number' && isFinite(v) ? (100 * v).toFixed(1) + ' %' : '-';
  }

  function table(headers, rows, cls) {
    return el('table', { class: cls || 'data' },
      el('thead', {}, el('tr', {}, headers.map((h) => el('th', {}, h)))),
      el('tbody', {}, rows.map((r) => el('tr', {}, r.map((c) => (c instanceof Node ? c : el('td', {}, c === undefined ? '' : String(c))))))));
  }

  function section(root, id, title, source) {
    const s = el('section', { id: id }, el('h2', {}, title));
    if (source) s.appendChild(el('p', { class: 'source' }, source));
    root.appendChild(s);
    return s;
  }

  function note(parent, text) {
    parent.appendChild(el('p', { class: 'note' }, text));
  }

  // Inverse of the standard normal CDF (Acklam's rational approximation, |error| < 1.2e-9):
  // the half-normal plot's quantiles.
  function normalQuantile(p) {
    const a = [-39.69683028665376, 220.9460984245205, -275.9285104469687, 138.357751867269, -30.66479806614716, 2.506628277459239];
    const b = [-54.47609879822406, 161.5858368580409, -155.6989798598866, 66.80131188771972, -13.28068155288572];
    const c = [-0.007784894002430293, -0.3223964580411365, -2.400758277161838, -2.549732539343734, 4.374664141464968, 2.938163982698783];
    const d = [0.007784695709041462, 0.3224671290700398, 2.445134137142996, 3.754408661907416];
    const lo = 0.02425;
    if (p < lo) {
      const q = Math.sqrt(-2 * Math.log(p));
      return (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) / ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
    }
    if (p > 1 - lo) return -normalQuantile(1 - p);
    const q = p - 0.5;
    const r = q * q;
    return ((((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q) / (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1);
  }

  // ---- plots ----

  function plot(parent, name, spec, caption) {
    const div = el('div', { class: 'plot', 'data-plot': name });
    const fig = el('figure', {}, div, caption ? el('figcaption', {}, caption) : null);
    parent.appendChild(fig);
    state.expected += 1;
    spec.$schema = 'https://vega.github.io/schema/vega-lite/v6.json';
    spec.config = Object.assign({ font: 'sans-serif', view: { stroke: '#ccc' } }, spec.config || {});
    vegaEmbed(div, spec, { renderer: 'svg', actions: false })
      .then((result) => {
        state.views.push(result.view);
        state.rendered += 1;
        div.setAttribute('data-rendered', 'true');
        updateStatus();
      })
      .catch((err) => {
        state.failed += 1;
        console.error('plot ' + name + ': ' + err);
        updateStatus();
      });
  }

  function updateStatus() {
    const s = document.getElementById('demcal-status');
    if (!s) return;
    s.setAttribute('data-plots-expected', state.expected);
    s.setAttribute('data-plots-rendered', state.rendered);
    s.setAttribute('data-plots-failed', state.failed);
    s.textContent = state.rendered + ' of ' + state.expected + ' plots drawn' + (state.failed ? ', ' + state.failed + ' failed' : '');
  }

  const SIG_COLOURS = { domain: ['> SME', '> ME', 'not active'], range: ['#c0392b', '#e67e22', '#7f8c8d'] };

  function significance(e) {
    return e.active_sme ? '> SME' : e.active_me ? '> ME' : 'not active';
  }

  function lenthRules(m) {
    return [
      { limit: 'ME', value: m.me },
      { limit: 'SME', value: m.sme },
    ].filter((r) => typeof r.value === 'number' && isFinite(r.value));
  }

  function halfNormalPlot(parent, m) {
    const sorted = m.effects.slice().sort((x, y) => Math.abs(x.effect) - Math.abs(y.effect));
    const n = sorted.length;
    const points = sorted.map((e, i) => ({
      chain: e.chain,
      abs_effect: Math.abs(e.effect),
      effect: e.effect,
      quantile: normalQuantile(0.5 + (0.5 * (i + 0.5)) / n),
      significance: significance(e),
      term: e.in_model === false ? 'residual contrast' : 'model term',
    }));
    plot(parent, 'half-normal:' + m.metric, {
      title: 'Half-normal plot of effects: ' + m.metric,
      width: 330, height: 260,
      layer: [
        {
          data: { values: points },
          mark: { type: 'point', filled: true, size: 60 },
          encoding: {
            x: { field: 'abs_effect', type: 'quantitative', title: '|effect|' },
            y: { field: 'quantile', type: 'quantitative', title: 'half-normal quantile' },
            color: { field: 'significance', type: 'nominal', scale: SIG_COLOURS, title: 'Lenth' },
            shape: { field: 'term', type: 'nominal', title: 'term' },
            tooltip: [{ field: 'chain' }, { field: 'effect', format: '.4g' }],
          },
        },
        {
          data: { values: points },
          mark: { type: 'text', align: 'left', dx: 6, fontSize: 10 },
          encoding: {
            x: { field: 'abs_effect', type: 'quantitative' },
            y: { field: 'quantile', type: 'quantitative' },
            text: { field: 'chain' },
          },
        },
        {
          data: { values: lenthRules(m) },
          mark: { type: 'rule', strokeDash: [4, 3] },
          encoding: {
            x: { field: 'value', type: 'quantitative' },
            color: { field: 'limit', type: 'nominal', scale: { domain: ['ME', 'SME'], range: ['#e67e22', '#c0392b'] }, legend: null },
          },
        },
      ],
      resolve: { scale: { color: 'independent' } },
    }, 'Points: |effect| of every alias chain against half-normal quantiles (Daniel 1959); dashed lines: Lenth (1989) ME (orange) and SME (red). Not a figure of seed 000, which reads its effects from main-effect plots only.');
  }

  function paretoPlot(parent, m) {
    const bars = m.effects.map((e) => ({ chain: e.chain, abs_effect: Math.abs(e.effect), effect: e.effect, significance: significance(e) }));
    plot(parent, 'pareto:' + m.metric, {
      title: 'Pareto chart of effects: ' + m.metric,
      width: 330, height: Math.max(120, 18 * bars.length),
      layer: [
        {
          data: { values: bars },
          mark: 'bar',
          encoding: {
            y: { field: 'chain', type: 'nominal', sort: '-x', title: 'alias chain' },
            x: { field: 'abs_effect', type: 'quantitative', title: '|effect|' },
            color: { field: 'significance', type: 'nominal', scale: SIG_COLOURS, title: 'Lenth' },
            tooltip: [{ field: 'chain' }, { field: 'effect', format: '.4g' }],
          },
        },
        {
          data: { values: lenthRules(m) },
          mark: { type: 'rule', strokeDash: [4, 3], color: '#333' },
          encoding: { x: { field: 'value', type: 'quantitative' } },
        },
        {
          data: { values: lenthRules(m) },
          mark: { type: 'text', dy: -4, align: 'left', dx: 3, fontSize: 10 },
          encoding: { x: { field: 'value', type: 'quantitative' }, y: { value: 0 }, text: { field: 'limit' } },
        },
      ],
    }, 'Bars: |effect| per alias chain, largest first; lines: Lenth ME and SME.');
  }

  // The design's runs joined with their finished design jobs: one row per run and response.
  function runResponses(data) {
    const d = data.export.design;
    const rows = [];
    for (const job of data.export.jobs) {
      if (job.kind !== 'design' || job.state !== 'done' || !job.std_order) continue;
      const i = job.std_order - 1;
      if (!d.coded[i]) continue;
      for (const [metric, value] of Object.entries(job.metrics || {})) {
        rows.push({ response: job.test + '.' + metric, run: job.std_order, coded: d.coded[i], centre: d.point_type[i] !== 0, value: value });
      }
    }
    return rows;
  }

  function factorLabels(data) {
    const names = data.export.design.factor_names;
    return names.map((n, i) => String.fromCharCode(65 + i) + ' = ' + n);
  }

  function mainEffectsPlot(parent, metric, rows, labels) {
    const values = [];
    for (const r of rows) {
      if (r.response !== metric) continue;
      labels.forEach((label, f) => values.push({ factor: label, level: r.centre ? 0 : r.coded[f], point: r.centre ? 'centre' : 'factorial', value: r.value }));
    }
    if (values.length === 0) return false;
    plot(parent, 'main-effects:' + metric, {
      title: 'Main effects: ' + metric,
      data: { values: values },
      facet: { field: 'factor', type: 'nominal', title: null },
      columns: Math.min(4, labels.length),
      spec: {
        width: 150, height: 130,
        layer: [
          {
            transform: [{ filter: "datum.point === 'factorial'" }],
            mark: { type: 'line', point: true },
            encoding: {
              x: { field: 'level', type: 'quantitative', title: 'coded level', scale: { domain: [-1.2, 1.2] }, axis: { values: [-1, 0, 1] } },
              y: { aggregate: 'mean', field: 'value', type: 'quantitative', title: 'mean ' + metric, scale: { zero: false } },
            },
          },
          {
            transform: [{ filter: "datum.point === 'centre'" }],
            mark: { type: 'point', shape: 'diamond', color: '#c0392b', filled: true, size: 70 },
            encoding: {
              x: { field: 'level', type: 'quantitative' },
              y: { aggregate: 'mean', field: 'value', type: 'quantitative' },
            },
          },
        ],
      },
      resolve: { scale: { y: 'shared' } },
    }, 'Mean response at the low and high level of each factor (line) and at the centre points (red diamond, where the design has them), as seed 000 Figs. 15, 18-22 and 24-26.');
    return true;
  }

  // The two-factor interactions worth a plot: the first word of each 2FI alias chain, largest
  // effects first (the effect table is already sorted), at most three.
  function interactionPairs(m, nFactors) {
    const pairs = [];
    for (const e of m.effects) {
      const first = e.chain.split('=')[0].replace(/^-/, '').trim();
      if (!/^[A-Z]{2}$/.test(first)) continue;
      const a = first.charCodeAt(0) - 65;
      const b = first.charCodeAt(1) - 65;
      if (a < nFactors && b < nFactors) pairs.push({ chain: e.chain, a: a, b: b });
      if (pairs.length === 3) break;
    }
    return pairs;
  }

  function interactionPlot(parent, metric, rows, labels, pair) {
    const values = rows
      .filter((r) => r.response === metric && !r.centre)
      .map((r) => ({ x: r.coded[pair.a], trace: labels[pair.b] + (r.coded[pair.b] > 0 ? ' high' : ' low'), value: r.value }));
    if (values.length === 0) return;
    plot(parent, 'interaction:' + metric + ':' + pair.chain, {
      title: { text: 'Interaction ' + pair.chain, subtitle: metric },
      width: 220, height: 160,
      data: { values: values },
      mark: { type: 'line', point: true },
      encoding: {
        x: { field: 'x', type: 'quantitative', title: labels[pair.a] + ' (coded)', scale: { domain: [-1.2, 1.2] }, axis: { values: [-1, 1] } },
        y: { aggregate: 'mean', field: 'value', type: 'quantitative', title: 'mean', scale: { zero: false } },
        color: { field: 'trace', type: 'nominal', title: null, legend: { orient: 'bottom', direction: 'vertical', labelLimit: 300 } },
      },
    }, 'Mean response over ' + labels[pair.a] + ' at each level of ' + labels[pair.b] + '; non-parallel lines show the interaction (aliased as ' + pair.chain + '). Not a figure of seed 000, which fits 2FIs (§2.5.2) but plots none.');
  }

  // ---- sections ----

  function header(root, data) {
    const c = data.campaign;
    const p = c.progress || {};
    const finished = Number(p.done || 0) + Number(p.failed || 0);
    const total = Math.max(1, Number(p.total || 0) - Number(p.cancelled || 0));
    root.appendChild(el('header', {},
      el('h1', {}, 'Campaign ' + c.id + ': ' + c.name),
      el('p', {}, (c.spec && c.spec.description) || ''),
      el('p', { class: 'progress' },
        el('span', { id: 'campaign-state', 'data-state': c.state }, String(c.state).toLowerCase()),
        ' · ', finished + ' of ' + total + ' jobs finished',
        Number(p.failed) ? ' (' + p.failed + ' failed)' : '',
        Number(p.reused) ? ' (' + p.reused + ' reused: taken from earlier runs of the same run key)' : '',
        ' · ', Number(p.leased || 0) + ' running',
        ' · created ' + (c.created_at || '')),
      el('progress', { max: total, value: finished }),
      page.mode === 'live' ? el('p', { class: 'note', id: 'live-note' }, 'Live page: updated every ' + page.interval / 1000 + ' s from the coordinator.') : null));
  }

  function designSection(root, data) {
    const s = section(root, 'design', 'Design', 'The 2^(k-p) design as the coordinator built it (seed 000 §2.5, Tables 7-8).');
    const sum = data.design.summary || {};
    s.appendChild(el('p', {}, sum.description + ': ' + sum.runs + ' runs, ' + sum.jobs + ' jobs, resolution ' + sum.resolution + (sum.generators ? ', generators ' + sum.generators : '')));
    s.appendChild(el('h3', {}, 'Factors'));
    s.appendChild(el('ul', {}, (sum.factor_letters || []).map((f) => el('li', {}, f))));
    if ((sum.defining_relation || []).length) s.appendChild(el('p', {}, 'Defining relation: I = ' + sum.defining_relation.join(' = ')));
    if ((sum.main_effect_alias_chains || []).length) {
      s.appendChild(el('h3', {}, 'Main effects aliased with 2FIs'));
      s.appendChild(el('ul', {}, sum.main_effect_alias_chains.map((c) => el('li', {}, c))));
    }
    if ((sum.two_factor_alias_chains || []).length) {
      s.appendChild(el('h3', {}, '2FI alias chains (' + sum.two_factor_alias_chains.length + ')'));
      s.appendChild(el('ul', { class: 'chains' }, sum.two_factor_alias_chains.map((c) => el('li', {}, c))));
    }
    s.appendChild(el('p', {}, 'Clear 2FIs: ' + ((sum.clear_two_factor_interactions || []).join(' ') || 'none')));

    s.appendChild(el('h3', {}, 'Run table'));
    const factors = data.design.factors || [];
    const results = {};
    for (const job of data.export.jobs) {
      if (job.kind !== 'design') continue;
      for (const [metric, v] of Object.entries(job.metrics || {})) {
        results[job.std_order] = results[job.std_order] || {};
        results[job.std_order][job.test + '.' + metric] = v;
      }
    }
    const responses = data.export.design.responses || [];
    const rows = (data.design.runs || []).map((r) => [r.std_order, r.run_order, r.point_type, r.replicate]
      .concat(r.natural.map((v) => fmt(v, 4)))
      .concat(responses.map((resp) => fmt((results[r.std_order] || {})[resp]))));
    s.appendChild(table(['std', 'run', 'point', 'rep'].concat(factors).concat(responses), rows, 'data runs'));
  }

  function effectsSection(root, data) {
    const s = section(root, 'effects', 'Effects per metric', 'Effects E = mean(high) - mean(low) per alias chain (seed 000 §2.5.2) with Lenth significance, as `demcal effects --format json` gives them; main-effect plots as seed 000 Figs. 15, 18-22, 24-26.');
    if (!data.effects) {
      note(s, 'No effects yet: ' + (data.notes.effects || 'the design runs are not finished'));
      return;
    }
    const rows = runResponses(data);
    const labels = factorLabels(data);
    for (const m of data.effects.metrics) {
      const ms = el('div', { class: 'metric', 'data-metric': m.metric, 'data-me': m.me, 'data-sme': m.sme, 'data-pse': m.pse });
      s.appendChild(ms);
      ms.appendChild(el('h3', {}, m.metric + ' (' + m.runs_used + ' of ' + m.runs_total + ' runs)'));
      if (!m.effects || m.effects.length === 0) {
        note(ms, (m.notes || []).join('; ') || 'no effects');
        continue;
      }
      ms.appendChild(el('p', {},
        'Lenth on the ' + m.lenth_terms + ' model terms: PSE ', el('span', { class: 'num', 'data-field': 'pse', 'data-value': m.pse }, fmt(m.pse)),
        ', ME ', el('span', { class: 'num', 'data-field': 'me', 'data-value': m.me }, fmt(m.me)),
        ', SME ', el('span', { class: 'num', 'data-field': 'sme', 'data-value': m.sme }, fmt(m.sme)),
        ' (t with ' + fmt(m.lenth_df, 3) + ' df); mean ' + fmt(m.intercept) + ', R² ' + fmt(m.r_squared, 4)));
      const grid = el('div', { class: 'grid' });
      ms.appendChild(grid);
      halfNormalPlot(grid, m);
      paretoPlot(grid, m);
      ms.appendChild(table(['alias chain', 'effect', 'Lenth'], m.effects.map((e) => [
        e.chain,
        el('td', { class: 'num effect', 'data-chain': e.chain, 'data-value': e.effect }, fmt(e.effect)),
        significance(e) + (e.in_model === false ? ' (residual)' : ''),
      ]), 'data effects'));
      mainEffectsPlot(ms, m.metric, rows, labels);
      const pairs = interactionPairs(m, labels.length);
      if (pairs.length) {
        const ig = el('div', { class: 'grid small' });
        ms.appendChild(ig);
        for (const pair of pairs) interactionPlot(ig, m.metric, rows, labels, pair);
      }
    }
  }

  function envelopeSection(root, data) {
    const s = section(root, 'envelope', 'Envelope against the measured targets', 'What the fitted models reach over the factor box against each measured value with its uncertainty (seed 000 Tables 10 and 13).');
    const cal = data.calibration;
    if (!cal) {
      note(s, data.notes.calibration || 'no calibration');
      return;
    }
    // While a round runs its prediction is shown; while a stage's design runs there is none.
    const rounds = cal.rounds || [];
    const predicted = cal.fitted || (rounds.length > 0 && rounds[rounds.length - 1].state === 'running');
    for (const m of cal.metrics) {
      const tol = m.tolerance > 0 ? m.tolerance : m.uncertainty;
      // While a calibration round runs the models are not refitted: no reach to draw.
      const marks = cal.fitted ? [
        { what: 'reach of the models', lo: m.envelope_min, hi: m.envelope_max, y: 'envelope' },
      ] : [];
      const pts = [{ what: 'measured', x: m.target, y: 'measured', lo: m.target - (m.uncertainty || 0), hi: m.target + (m.uncertainty || 0) }];
      if (tol > 0) pts.push({ what: 'tolerance', x: m.target, y: 'tolerance', lo: m.target - tol, hi: m.target + tol });
      if (predicted) pts.push({ what: 'predicted', x: m.predicted, y: 'predicted', lo: m.predicted, hi: m.predicted });
      if (m.simulated_available) pts.push({ what: 'simulated', x: m.simulated, y: 'simulated', lo: m.simulated, hi: m.simulated });
      const order = ['envelope', 'measured', 'tolerance', 'predicted', 'simulated'];
      plot(s, 'envelope:' + m.metric, {
        title: m.metric,
        width: 480, height: 110,
        layer: [
          { data: { values: marks }, mark: { type: 'bar', height: 12, color: '#aec7e8' }, encoding: { x: { field: 'lo', type: 'quantitative', title: m.metric, scale: { zero: false } }, x2: { field: 'hi' }, y: { field: 'y', type: 'nominal', sort: order, title: null } } },
          { data: { values: pts }, mark: { type: 'rule', strokeWidth: 2 }, encoding: { x: { field: 'lo', type: 'quantitative' }, x2: { field: 'hi' }, y: { field: 'y', type: 'nominal', sort: order }, color: { field: 'what', type: 'nominal', legend: null } } },
          { data: { values: pts }, mark: { type: 'point', filled: true, size: 70 }, encoding: { x: { field: 'x', type: 'quantitative' }, y: { field: 'y', type: 'nominal', sort: order }, color: { field: 'what', type: 'nominal', legend: null }, tooltip: [{ field: 'what' }, { field: 'x', format: '.5g' }] } },
        ],
      }, m.statement || '');
    }
  }

  // A multi-fidelity campaign: per response the high level's model from the low one, low against
  // high at the rows run at both levels, and the particle-steps of each level (docs/doe.md).
  function fidelityPart(s, cal) {
    if (!cal.fidelity || !cal.fidelity.length) return;
    s.appendChild(el('h3', {}, 'High fidelity level from the low one'));
    s.appendChild(table(['response', 'model', 'rho', 'high - low (mean)', 'correction sd', 'rows at both levels'], cal.fidelity.map((f) => [
      f.response, f.model, fmt(f.rho, 4), fmt(f.mean_bias, 4), fmt(f.correction_sd, 3), (f.rows || []).join(', '),
    ])));
    const pairs = [];
    for (const f of cal.fidelity) (f.rows || []).forEach((r, i) => pairs.push({ response: f.response, row: r, low: f.low[i], high: f.high[i] }));
    s.appendChild(table(['response', 'row', 'low', 'high'], pairs.map((p) => [p.response, p.row, fmt(p.low, 5), fmt(p.high, 5)])));
    const c = cal.fidelity_cost || {};
    const design = Number(c.low_particle_steps || 0) + Number(c.high_particle_steps || 0);
    const all = Number(c.all_high_particle_steps || 0);
    s.appendChild(el('p', {}, 'Particle-steps: low ' + fmt(Number(c.low_particle_steps || 0), 4) + ' (' + (c.low_jobs || 0) + ' jobs), high ' +
      fmt(Number(c.high_particle_steps || 0), 4) + ' (' + (c.high_jobs || 0) + ' jobs), verification ' + fmt(Number(c.verify_particle_steps || 0), 4) +
      ' (' + (c.verify_jobs || 0) + ' jobs); the design at the high level in every row: ' + fmt(all, 4) +
      (all > 0 ? ' (this design: ' + Math.round(100 * design / all) + ' %)' : '') + '.'));
  }

  function calibrationSection(root, data) {
    const s = section(root, 'calibration', 'Calibration rounds and verified errors', 'The proposed set, predicted / simulated / measured and deviations, round by round (seed 000 §3.3, Tables 12 and 15).');
    const cal = data.calibration;
    if (!cal) {
      note(s, data.notes.calibration || 'no calibration');
      return;
    }
    s.appendChild(el('p', {}, 'Conclusion: ' + (cal.conclusion || cal.verification_state)));
    s.appendChild(table(['factor', 'proposed'], cal.factor_paths.map((f, i) => [f, fmt(cal.proposed_values[i], 6)])));
    const identifiability = (cal.intervals || []).map((i) => i.statement)
      .concat((cal.trade_offs || []).map((t) => t.statement));
    if (identifiability.length) s.appendChild(el('ul', { class: 'identifiability' }, identifiability.map((text) => el('li', {}, text))));
    s.appendChild(table(['metric', 'measured', 'predicted', 'simulated', 'error', 'tolerance', 'within'], cal.metrics.map((m) => [
      m.metric, fmt(m.target), fmt(m.predicted), m.simulated_available ? fmt(m.simulated) : '-', pct(m.relative_error), fmt(m.tolerance, 3),
      m.simulated_available ? (m.within ? 'yes' : 'no') : '-',
    ])));
    const verified = cal.metrics.filter((m) => m.simulated_available && m.tolerance > 0)
      .map((m) => ({ metric: m.metric, deviation: (m.simulated - m.target) / m.tolerance }));
    if (verified.length) {
      plot(s, 'verified-errors', {
        title: 'Verified error of the proposed set, in tolerances',
        width: 420, height: Math.max(60, 24 * verified.length),
        layer: [
          { data: { values: verified }, mark: 'bar', encoding: { y: { field: 'metric', type: 'nominal', title: null }, x: { field: 'deviation', type: 'quantitative', title: '(simulated - measured) / tolerance' }, color: { condition: { test: 'abs(datum.deviation) <= 1', value: '#2ca02c' }, value: '#d62728' } } },
          { data: { values: [{ x: -1 }, { x: 1 }] }, mark: { type: 'rule', strokeDash: [4, 3] }, encoding: { x: { field: 'x', type: 'quantitative' } } },
        ],
      }, 'Bars inside the dashed lines are within tolerance = sqrt(uncertainty² + noise sd²).');
    }
    fidelityPart(s, cal);
    const rounds = (data.campaign.calibration_rounds || []).filter((r) => r.state === 'done');
    if (rounds.length) {
      plot(s, 'calibration-rounds', {
        title: 'Sequential calibration: worst deviation per round',
        width: 420, height: 180,
        layer: [
          { data: { values: rounds.map((r) => ({ round: r.round, stage: 'stage ' + r.stage, worst: r.worst_deviation, metric: r.worst_metric })) }, mark: { type: 'line', point: true }, encoding: { x: { field: 'round', type: 'ordinal' }, y: { field: 'worst', type: 'quantitative', title: 'worst |simulated - measured| / tolerance' }, color: { field: 'stage', type: 'nominal' }, tooltip: [{ field: 'metric' }, { field: 'worst', format: '.3g' }] } },
          { data: { values: [{ y: 1 }] }, mark: { type: 'rule', strokeDash: [4, 3] }, encoding: { y: { field: 'y', type: 'quantitative' } } },
        ],
      }, 'Each round verifies a proposal by simulation; below the dashed line every metric is within tolerance.');
      s.appendChild(table(['round', 'stage', 'state', 'within', 'worst metric', 'worst / tolerance', 'proposed'], data.campaign.calibration_rounds.map((r) => [
        r.round, r.stage, r.state, r.within ? 'yes' : 'no', r.worst_metric, fmt(r.worst_deviation, 3), r.proposed_values.map((v) => fmt(v, 4)).join(', '),
      ])));
    } else {
      note(s, 'No verification round finished yet.');
    }
  }

  function diagnosisSection(root, data) {
    const s = section(root, 'diagnosis', 'Diagnosis', 'What the calibrated model gets wrong and the candidate causes tested by simulation (seed 000 §4; docs/diagnosis.md).');
    const d = data.diagnosis;
    if (!d || !d.report) {
      note(s, data.notes.diagnosis || (d && d.conclusion) || 'no diagnosis');
      return;
    }
    const r = d.report;
    s.appendChild(el('p', {}, 'State: ' + d.state + '. ' + (r.conclusion || d.conclusion || '')));
    if (d.named_cause) s.appendChild(el('p', { class: 'named' }, 'Named cause: ' + d.named_cause));
    if ((r.rivals || []).length) s.appendChild(el('p', {}, 'Not told apart from it by these data (verified within the margin of its error): ' + r.rivals.join(', ')));
    const b = r.baseline || {};
    const withSe = (v, se) => pct(v) + (typeof se === 'number' ? ' ± ' + pct(se) : '');
    s.appendChild(el('p', {}, 'Baseline RMS error: predicted ' + pct(b.predicted_rms) + ', verified ' + withSe(b.verified_rms, b.verified_rms_se) + ', held out ' + withSe(b.holdout_rms, b.holdout_rms_se)));
    const cands = r.candidates || [];
    // The held-out misfit's cause is named apart from the calibrated one (docs/diagnosis.md).
    const heldOut = cands.find((c) => c.id === r.holdout_cause);
    if (heldOut) {
      s.appendChild(el('p', { class: 'named', 'data-holdout-cause': heldOut.id, 'data-holdout-gain': heldOut.holdout_gain },
        'Named cause of the held-out misfit: ' + heldOut.cause + '; held out ' + withSe(heldOut.holdout_rms, heldOut.holdout_rms_se) + ' against the baseline\'s ' + withSe(b.holdout_rms, b.holdout_rms_se) + ', a gain of ' + pct(heldOut.holdout_gain)));
    }
    s.appendChild(table(['candidate', 'runs', 'predicted', 'verified', 'round (best/done)', 'held out', 'gain', 'explains', 'cause', 'state'], cands.map((c) => [
      c.id, c.runs, pct(c.predicted_rms), withSe(c.verified_rms, c.verified_rms_se), (c.best_round || 0) + '/' + (c.rounds || 0), withSe(c.holdout_rms, c.holdout_rms_se), pct(c.holdout_gain), c.explains_label, c.cause, c.state,
    ]), 'data diagnosis-candidates'));
    const bars = [{ model: 'baseline', verified_rms: b.verified_rms }].concat(cands.map((c) => ({ model: c.id, verified_rms: c.verified_rms })))
      .filter((x) => typeof x.verified_rms === 'number');
    if (bars.length) {
      plot(s, 'diagnosis-errors', {
        title: 'Verified RMS error before (baseline) and after each candidate',
        width: 420, height: Math.max(60, 24 * bars.length),
        data: { values: bars },
        mark: 'bar',
        encoding: { y: { field: 'model', type: 'nominal', sort: null, title: null }, x: { field: 'verified_rms', type: 'quantitative', title: 'verified RMS relative error', axis: { format: '%' } }, color: { condition: { test: "datum.model === 'baseline'", value: '#7f8c8d' }, value: '#1f77b4' } },
      });
    }
    if ((r.conflicts || []).length) s.appendChild(el('ul', {}, r.conflicts.map((c) => el('li', {}, c.statement))));
    const flagged = (r.metrics || []).flatMap((m) => (m.notes || []).map((n) => m.response + ': ' + n));
    if (flagged.length) {
      s.appendChild(el('p', {}, 'Flagged values the diagnosis uses:'));
      s.appendChild(el('ul', { class: 'flagged' }, flagged.map((f) => el('li', {}, f))));
    }
  }

  // The curves of each lab test (docs/lab-tests.md names the series, docs/report.md the figures):
  // per plot the series, its x and y columns, the axis titles and the seed's figure it follows.
  const CURVES = {
    confined_compression: [{ series: 'stress_strain', x: 'strain', y: 'stress_kPa', xTitle: 'strain (h - h1) / h1', yTitle: 'piston stress (kPa)', title: 'stress-strain cycles', caption: 'Load-unload cycles of every finished job, strain as seed 000 Fig. 8.' }],
    tensile: [{ series: 'tensile', x: 'strain', y: 'tensile_stress_kPa', xTitle: 'strain', yTitle: 'tensile stress (kPa)', title: 'tensile stress against strain', caption: 'The pull of every finished job (seed 000 Fig. 11, §2.7.3).' }],
    wall_friction: [{ series: 'wall_shear', x: 'normal_stress_kPa', y: 'shear_stress_kPa', xTitle: 'normal stress (kPa)', yTitle: 'wall shear stress (kPa)', title: 'wall yield locus', points: true, caption: 'Wall shear stress against normal stress (seed 000 §2.7.5); the slope of the line through the origin is the wall friction.' }],
    rotating_drum: [
      { series: 'surface_profile', x: 'x_m', y: 'y_m', xTitle: 'x (m)', yTitle: 'y (m)', title: 'free surface in the drum', drum: true, points: true, caption: 'The free surface of the last image of the angle window (seed 001 §3.2.2) inside the drum wall.' },
      { series: 'angle', x: 'time', y: 'angle_deg', xTitle: 'time (s)', yTitle: 'surface angle (deg)', title: 'dynamic angle over time', caption: 'The surface angle of every image; the metric is the mean of the second half.' },
    ],
    hopper: [{ series: 'discharge', x: 'time', y: 'discharged_mass', xTitle: 'time (s)', yTitle: 'discharged mass (kg)', title: 'hopper mass against time', caption: 'Discharged mass of every finished job (seed 000 §2.7.6); the rate is the slope between 15 % and 75 % of it.' }],
  };

  function jobLabel(job) {
    return 'job ' + job.job_id + ' (' + job.kind + ' ' + job.std_order + ')';
  }

  // The rows of `series` as points {job, i, x, y}, or none when it lacks a column.
  function curvePoints(job, series, x, y) {
    const s = (job.series || {})[series];
    if (!s) return [];
    const ix = s.columns.indexOf(x), iy = s.columns.indexOf(y);
    if (ix < 0 || iy < 0) return [];
    return s.rows.map((r, i) => ({ job: jobLabel(job), i: i, x: r[ix], y: r[iy] }));
  }

  // Points of the upper half of a circle (sigma, tau) for a Mohr circle.
  function circlePoints(job, circle, centre, radius) {
    const out = [];
    for (let k = 0; k <= 60; ++k) {
      const t = (Math.PI * k) / 60;
      out.push({ job: jobLabel(job), circle: circle, i: k, x: centre + radius * Math.cos(t), y: radius * Math.sin(t) });
    }
    return out;
  }

  // One line per job (and per circle), its points in row order; `axes` gives the axis titles.
  function lineLayer(values, axes, points, strokeDash) {
    return {
      data: { values: values },
      mark: { type: 'line', point: points ? { filled: true, size: 30 } : false, strokeDash: strokeDash },
      encoding: {
        x: { field: 'x', type: 'quantitative', scale: { zero: false }, title: axes.xTitle },
        y: { field: 'y', type: 'quantitative', scale: { zero: false }, title: axes.yTitle },
        color: { field: 'job', type: 'nominal', legend: { title: null } },
        detail: { field: 'circle', type: 'nominal' },
        order: { field: 'i', type: 'quantitative' },
        tooltip: [{ field: 'job' }, { field: 'x', format: '.4g' }, { field: 'y', format: '.4g' }],
      },
    };
  }

  function curvePlot(parent, name, jobs, c) {
    const values = jobs.flatMap((j) => curvePoints(j, c.series, c.x, c.y));
    if (!values.length) return false;
    const layers = [lineLayer(values, c, c.points)];
    if (c.drum) {
      // the drum wall: a circle of the job's drum_diameter about the axis
      const wall = jobs.filter((j) => j.metrics && j.metrics.drum_diameter > 0).slice(0, 1)
        .flatMap((j) => [...circlePoints(j, 'upper', 0, j.metrics.drum_diameter / 2), ...circlePoints(j, 'lower', 0, j.metrics.drum_diameter / 2).map((p) => Object.assign(p, { y: -p.y }))]);
      if (wall.length) layers.push({ data: { values: wall }, mark: { type: 'line', color: '#999' }, encoding: { x: { field: 'x', type: 'quantitative' }, y: { field: 'y', type: 'quantitative' }, detail: { field: 'circle', type: 'nominal' }, order: { field: 'i', type: 'quantitative' } } });
    }
    plot(parent, name, {
      title: c.title,
      width: c.drum ? 300 : 420, height: c.drum ? 300 : 260,
      layer: layers,
    }, c.caption);
    return true;
  }

  // Seed 000 Fig. 23: the measured yield points, the fitted locus and its Mohr circles per job.
  function yieldLocusPlot(parent, name, jobs) {
    const perJob = jobs.map((j) => curvePoints(j, 'yield_points', 'sigma_measured_kpa', 'yield_shear_stress_kpa'));
    const points = perJob.flat();
    if (!points.length) return false;
    const loci = [], circles = [];
    jobs.forEach((j, k) => {
      const m = j.metrics || {};
      const top = Math.max(...perJob[k].map((p) => p.x), m.major_consolidation_stress || 0);
      if (typeof m.yield_locus_slope === 'number' && isFinite(top))
        for (const x of [0, top]) loci.push({ job: jobLabel(j), i: x, x: x, y: m.yield_locus_intercept + m.yield_locus_slope * x });
      const s = (j.series || {}).mohr_circles;
      if (s) for (const r of s.rows) circles.push(...circlePoints(j, String(r[0]), r[1], r[2]));
    });
    const axes = { xTitle: 'normal stress (kPa)', yTitle: 'shear stress (kPa)' };
    const layers = [
      { data: { values: points }, mark: { type: 'point', filled: true, size: 50 }, encoding: { x: { field: 'x', type: 'quantitative', title: axes.xTitle }, y: { field: 'y', type: 'quantitative', title: axes.yTitle }, color: { field: 'job', type: 'nominal', legend: { title: null } }, tooltip: [{ field: 'job' }, { field: 'x', format: '.4g' }, { field: 'y', format: '.4g' }] } },
      lineLayer(loci, axes, false, [6, 3]),
    ];
    if (circles.length) layers.push(lineLayer(circles, axes, false));
    plot(parent, name, {
      title: 'yield locus and Mohr circles',
      width: 420, height: 260,
      layer: layers,
    }, 'Yield points at the normal stresses of the test, the fitted locus (dashed) and the Mohr circles of the unconfined yield strength and of the consolidation (seed 000 Fig. 23).');
    return true;
  }

  function labCurves(parent, t, name, jobs) {
    let drawn = 0;
    if (t.test === 'shear_cell') drawn += yieldLocusPlot(parent, 'curve:' + name + ':yield_locus', jobs);
    for (const c of CURVES[t.test] || []) drawn += curvePlot(parent, 'curve:' + name + ':' + c.series, jobs, c);
    if (!drawn && (CURVES[t.test] || t.test === 'shear_cell')) note(parent, 'No curves stored for the finished jobs of ' + name + '.');
  }

  function labSection(root, data) {
    const s = section(root, 'lab-tests', 'Lab tests', 'Per lab test instance its curves and its metrics over the runs (docs/lab-tests.md).');
    const tests = (data.campaign.spec && data.campaign.spec.tests) || [];
    for (const t of tests) {
      const name = t.name || t.test;
      const ts = el('div', { class: 'lab', 'data-test': name });
      s.appendChild(ts);
      ts.appendChild(el('h3', {}, name + ' (' + t.test + ')'));
      const done = data.export.jobs.filter((job) => job.test === name && job.state === 'done');
      if (done.length === 0) {
        note(ts, 'No finished job yet.');
        continue;
      }
      labCurves(ts, t, name, done);
      const values = [];
      for (const job of done)
        for (const [metric, v] of Object.entries(job.metrics || {})) values.push({ metric: metric, value: v, run: job.std_order, kind: job.kind.split(':')[0] });
      plot(ts, 'lab:' + name, {
        title: name + ': metrics of every finished job',
        data: { values: values },
        facet: { field: 'metric', type: 'nominal', title: null },
        columns: 3,
        spec: { width: 180, height: 120, mark: { type: 'point', filled: true }, encoding: { x: { field: 'kind', type: 'nominal', title: null }, y: { field: 'value', type: 'quantitative', scale: { zero: false }, title: null }, color: { field: 'kind', type: 'nominal', legend: null }, tooltip: [{ field: 'run' }, { field: 'value', format: '.5g' }] } },
        resolve: { scale: { y: 'independent' } },
      }, 'Each point one job: design runs, verification rounds and diagnosis runs.');
    }
  }

  function jobsSection(root, data) {
    const running = data.export.jobs.filter((j) => j.state === 'leased');
    const s = section(root, 'jobs', 'Jobs running now', null);
    if (!running.length) {
      note(s, 'No job is running.');
      return;
    }
    s.appendChild(table(['job', 'test', 'kind', 'run', 'worker', 'attempt'], running.map((j) => [j.job_id, j.test, j.kind, j.std_order, j.worker, j.attempt])));
  }

  function notesSection(root, data) {
    const entries = Object.entries(data.notes || {});
    if (!entries.length) return;
    const s = section(root, 'notes', 'Notes', null);
    s.appendChild(el('ul', {}, entries.map(([k, v]) => el('li', {}, k + ': ' + v))));
  }

  function render(data) {
    for (const v of state.views) v.finalize();
    state.views = [];
    state.expected = state.rendered = state.failed = 0;
    const root = document.getElementById('report');
    root.textContent = '';
    header(root, data);
    if (page.mode === 'live') jobsSection(root, data);
    designSection(root, data);
    effectsSection(root, data);
    envelopeSection(root, data);
    calibrationSection(root, data);
    diagnosisSection(root, data);
    labSection(root, data);
    notesSection(root, data);
    updateStatus();
  }

  // ---- the live page: poll the JSON endpoint, redraw when it changed ----

  function bearer() {
    const m = /(?:^#|&)token=([^&]*)/.exec(window.location.hash);
    return m ? decodeURIComponent(m[1]) : '';
  }

  function poll() {
    const token = bearer();
    fetch(page.api, { headers: token ? { Authorization: 'Bearer ' + token } : {}, cache: 'no-store' })
      .then((r) => {
        if (!r.ok) throw new Error(page.api + ': HTTP ' + r.status);
        return r.text();
      })
      .then((text) => {
        if (text !== state.last) {
          state.last = text;
          (page.mode === 'index' ? renderIndex : render)(JSON.parse(text));
        }
        document.getElementById('demcal-status').setAttribute('data-polls', String(Number(document.getElementById('demcal-status').getAttribute('data-polls') || 0) + 1));
      })
      .catch((err) => console.error(String(err)))
      .finally(() => setTimeout(poll, page.interval));
  }

  // The live index: one line per campaign with its progress, linking to its live page (the
  // token fragment carried along).
  function renderIndex(list) {
    const root = document.getElementById('report');
    root.textContent = '';
    root.appendChild(el('h1', {}, 'demcal campaigns'));
    const rows = (list.campaigns || []).map((c) => {
      const p = c.progress || {};
      return [
        el('td', {}, el('a', { href: '/campaigns/' + c.id + window.location.hash }, String(c.id))),
        c.name, String(c.state).toLowerCase(), (Number(p.done || 0) + Number(p.failed || 0)) + ' of ' + (Number(p.total || 0) - Number(p.cancelled || 0)), String(p.leased || 0), c.created_at,
      ];
    });
    root.appendChild(table(['id', 'name', 'state', 'finished jobs', 'running', 'created'], rows));
  }

  function start() {
    if (page.mode === 'live' || page.mode === 'index') {
      poll();
    } else {
      render(JSON.parse(document.getElementById('demcal-data').textContent));
    }
  }

  if (document.readyState === 'loading') document.addEventListener('DOMContentLoaded', start);
  else start();
})();
