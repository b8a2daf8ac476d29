// The regressions pages' triage script (served from /assets so that the pages' CSP can forbid
// inline scripts): the write token once per browser session in sessionStorage, each group's
// form sent as JSON with `Authorization: Bearer`.
(() => {
  const KEY = 'tessera-write-token';
  const box = document.getElementById('token');
  const save = document.getElementById('token-save');
  const forget = document.getElementById('token-forget');
  const said = document.getElementById('token-state');
  const show = () => {
    const t = sessionStorage.getItem(KEY);
    said.textContent = t ? 'write token set for this browser session' : 'enter the write token once to triage in this browser session';
    box.hidden = save.hidden = !!t;
    forget.hidden = !t;
  };
  save.addEventListener('click', () => {
    const t = box.value.trim();
    if (t) { sessionStorage.setItem(KEY, t); box.value = ''; }
    show();
  });
  box.addEventListener('keydown', e => { if (e.key === 'Enter') { e.preventDefault(); save.click(); } });
  forget.addEventListener('click', () => { sessionStorage.removeItem(KEY); show(); });
  for (const f of document.querySelectorAll('form.triage')) {
    f.addEventListener('submit', async e => {
      e.preventDefault();
      const out = f.querySelector('.result');
      const t = sessionStorage.getItem(KEY);
      if (!t) { out.className = 'result failed'; out.textContent = 'enter the write token above first'; box.focus(); return; }
      const body = { state: f.elements.state.value, note: f.elements.note.value, bug_url: f.elements.bug_url.value };
      out.className = 'result'; out.textContent = 'saving…';
      try {
        const r = await fetch('/api/regressions/groups/' + encodeURIComponent(f.dataset.group || f.dataset.key), {
          method: 'POST',
          headers: { 'Content-Type': 'application/json', 'Authorization': 'Bearer ' + t },
          body: JSON.stringify(body),
        });
        const j = await r.json().catch(() => ({}));
        if (r.ok) {
          out.className = 'result ok';
          out.textContent = 'saved for ' + j.updated + ' series by ' + j.updated_by;
          const badge = document.querySelector('[data-state-of="' + CSS.escape(f.dataset.key) + '"]');
          if (badge) { badge.textContent = body.state; badge.className = 'badge st-' + body.state; }
        } else {
          out.className = 'result failed';
          out.textContent = (j.error || ('HTTP ' + r.status));
          if (r.status === 401) { sessionStorage.removeItem(KEY); show(); }
        }
      } catch (err) {
        out.className = 'result failed'; out.textContent = 'not saved: ' + err;
      }
    });
  }
  show();
})();
