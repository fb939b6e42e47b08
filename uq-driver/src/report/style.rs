//! The style sheet of the report's pages (inline in each page: no file to lose).

pub(super) const CSS: &str = "\
body{font-family:system-ui,-apple-system,'Segoe UI',Helvetica,Arial,sans-serif;color:#222;\
max-width:1100px;margin:0 auto;padding:24px;line-height:1.5;background:#fafafa}\
h1{font-size:1.7em;border-bottom:2px solid #ddd;padding-bottom:.3em}\
h2{font-size:1.3em;margin-top:2em;border-bottom:1px solid #e4e4e4;padding-bottom:.2em}\
nav ul{columns:2;padding-left:1.2em}\
figure{margin:1em 0;background:#fff;border:1px solid #e4e4e4;padding:8px;display:inline-block;\
max-width:100%;box-sizing:border-box;vertical-align:top}\
figure img{max-width:100%;height:auto;display:block}\
figcaption{font-size:.85em;color:#666;margin-top:4px}\
table{border-collapse:collapse;margin:1em 0;background:#fff;font-size:.92em}\
th,td{border:1px solid #ddd;padding:4px 10px;text-align:left}\
th{background:#f0f0f0}tr:nth-child(even) td{background:#f8f8f8}\
td.num{text-align:right;font-variant-numeric:tabular-nums}\
pre{background:#fff;border:1px solid #e4e4e4;padding:12px;overflow:auto;font-size:.85em}\
footer{margin-top:3em;color:#888;font-size:.8em}";
