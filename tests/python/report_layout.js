// Layout of the karst report as Chromium renders it (tests/cli/test_report_chromium.sh injects
// this script at the end of a copy of the page and reads the result from the dumped DOM).
// Measures, with the boxes the browser computed (getBoundingClientRect):
//   - every histogram bar (rect.bar) is at least MIN_BAR pixels wide and tall, and filled;
//   - no two <text> boxes of one plot overlap (by more than TOLERANCE pixels each way), and
//     every text lies inside its plot (nothing cut off at the edge);
//   - no text box overlaps a data mark (bars, petals, survey lines and points, published
//     bands, network lines, great circles, density cells);
//   - every plot with axes names its quantity and unit: a text with "(...)" under the x axis.
// Writes JSON into <pre id="karst-layout">.
(function () {
  const MIN_BAR = 2, TOLERANCE = 0.5;
  const out = {plots: 0, bars: 0, texts: 0, thin: [], unfilled: [], overlaps: [],
               on_data: [], unitless: [], clipped: []};
  const box = (el) => el.getBoundingClientRect();
  const cross = (a, b) =>
    Math.min(a.right, b.right) - Math.max(a.left, b.left) > TOLERANCE &&
    Math.min(a.bottom, b.bottom) - Math.max(a.top, b.top) > TOLERANCE;
  document.querySelectorAll('svg').forEach((svg, k) => {
    out.plots++;
    const t = svg.querySelector('title');
    const name = (t && t.textContent) || 'plot ' + k;
    svg.querySelectorAll('rect.bar').forEach((r) => {
      out.bars++;
      const b = box(r);
      if (b.width < MIN_BAR - 1e-6 || b.height < MIN_BAR - 1e-6)
        out.thin.push([name, +b.width.toFixed(2), +b.height.toFixed(2)]);
      const fill = getComputedStyle(r).fill;
      if (!fill || fill === 'none' || fill === 'rgb(255, 255, 255)') out.unfilled.push(name);
    });
    const texts = Array.from(svg.querySelectorAll('text')).filter((e) => e.textContent.trim())
      .map((e) => [e.textContent, box(e)]);
    out.texts += texts.length;
    const frame = box(svg);
    texts.forEach(([text, b]) => {
      if (b.left < frame.left - 1 || b.right > frame.right + 1 || b.top < frame.top - 1 ||
          b.bottom > frame.bottom + 1)
        out.clipped.push([name, text]);
    });
    for (let i = 0; i < texts.length; i++)
      for (let j = i + 1; j < texts.length; j++)
        if (cross(texts[i][1], texts[j][1]))
          out.overlaps.push([name, texts[i][0], texts[j][0]]);
    const marks = Array.from(svg.querySelectorAll(
      'rect.bar, rect.band, line.survey, path.survey, .survey circle, .survey polygon, ' +
      '.bar polygon, path.network, polyline.structure'));
    // Lines and polygons: their box is only a bound; a text is on them when it crosses the
    // box of a segment. Sample segments of paths and polylines finely enough for that.
    const pieces = [];
    marks.forEach((m) => {
      if (m.tagName === 'path' || m.tagName === 'polyline' || m.tagName === 'polygon') {
        const len = m.getTotalLength ? m.getTotalLength() : 0;
        const ctm = m.getScreenCTM();
        const steps = Math.min(2000, Math.ceil(len / 2));
        // Sub-paths (M commands) have no length between them: two samples farther apart than
        // a few steps straddle such a jump and are no segment.
        const jump = (3 * len) / Math.max(steps, 1) + 1;
        let prev = null;
        for (let s = 0; s <= steps && len > 0; s++) {
          const p = m.getPointAtLength((len * s) / steps).matrixTransform(ctm);
          if (prev && Math.hypot(p.x - prev.x, p.y - prev.y) <= jump)
            pieces.push({left: Math.min(p.x, prev.x), right: Math.max(p.x, prev.x),
                         top: Math.min(p.y, prev.y), bottom: Math.max(p.y, prev.y)});
          prev = p;
        }
      } else {
        pieces.push(box(m));
      }
    });
    const density = Array.from(svg.querySelectorAll('.density rect')).map(box);
    texts.forEach(([text, b]) => {
      const hit = pieces.find((p) => cross(
        {left: p.left - 0.5, right: p.right + 0.5, top: p.top - 0.5, bottom: p.bottom + 0.5}, b)) ||
        density.find((p) => cross(p, b));
      if (hit) out.on_data.push([name, text]);
    });
    // A plot with a y axis title (rotated text) is a plot with axes: the y title and an x
    // title (an unrotated text of class "axis") each give a unit in parentheses.
    const unit = (e) => /\(.+\)/.test(e.textContent);
    const rotated = Array.from(svg.querySelectorAll('g[transform*="rotate"] text'));
    const xtitles = Array.from(svg.querySelectorAll('text.axis'))
      .filter((e) => !e.closest('g[transform*="rotate"]'));
    if (rotated.length && (!rotated.every(unit) || !xtitles.some(unit)))
      out.unitless.push(name);
  });
  const pre = document.createElement('pre');
  pre.id = 'karst-layout';
  pre.textContent = JSON.stringify(out);
  document.body.appendChild(pre);
})();
