//! The report page's style sheet and script, inlined so the page needs no other file: the
//! script makes the before/after slider and the sortable metrics table work and, opened
//! as `index.html?selftest=1`, checks the page and writes its verdict as JSON into
//! `<pre id="selftest">`.

/// The style sheet.
pub const CSS: &str = r#"
:root{--fg:#1d2330;--muted:#667085;--line:#d9dee7;--bg:#f6f7f9;--card:#fff;--accent:#2563eb}
*{box-sizing:border-box}
body{font:14px/1.45 system-ui,-apple-system,"Segoe UI",Roboto,"DejaVu Sans",sans-serif;color:var(--fg);background:var(--bg);margin:0}
header{background:#141a26;color:#eef2f8;padding:18px 28px}
header h1{margin:0 0 4px;font-size:22px;font-weight:600}
header p{margin:0;color:#b8c2d3}
nav{position:sticky;top:0;z-index:5;background:#fff;border-bottom:1px solid var(--line);padding:6px 28px}
nav a{margin-right:16px;color:var(--accent);text-decoration:none}
main{padding:10px 28px 40px}
section{background:var(--card);border:1px solid var(--line);border-radius:8px;padding:14px 18px;margin:16px 0}
h2{font-size:17px;margin:0 0 10px}
.note{color:var(--muted);margin:4px 0 10px}
table{border-collapse:collapse;width:100%}
th,td{border-bottom:1px solid var(--line);padding:5px 8px;text-align:right;vertical-align:top}
th{background:#f0f2f6;cursor:pointer;user-select:none;white-space:nowrap}
th.text,td.text{text-align:left}
tr.reference-row td{background:#fbfbf2}
td.best{font-weight:700;color:#0a7a3b}
.stagebar{display:flex;height:9px;width:100%;border-radius:2px;overflow:hidden;background:#eee;margin:4px 0 3px}
.kv{display:inline-block;white-space:nowrap;margin-right:9px}
details summary{cursor:pointer;list-style:none}
details summary::-webkit-details-marker{display:none}
.more{color:var(--accent);white-space:nowrap}
td.params{max-width:230px}
td.stages{width:300px;text-align:left}
td.stages .kv{margin-right:6px}
tr td:first-child{white-space:nowrap}
td.counters{max-width:330px}
.stagebar span{display:block;height:100%}
.small{font-size:12px;color:var(--muted)}
.grid{display:flex;flex-wrap:wrap;gap:14px}
figure{margin:0}
figcaption{font-size:12px;color:var(--muted);margin-top:2px}
.pair{display:flex;gap:6px}
.pair img,.ref img{width:320px;display:block;border:1px solid var(--line)}
.frame{position:relative;display:inline-block}
.box{position:absolute;border:2px solid #ffd400;box-shadow:0 0 0 1px #000;pointer-events:none}
.slider-controls{display:flex;gap:14px;align-items:center;flex-wrap:wrap;margin-bottom:8px}
.slider{position:relative;display:inline-block;max-width:min(100%,1024px);cursor:ew-resize;touch-action:none;user-select:none;line-height:0}
.slider img{display:block;max-width:100%;height:auto}
#slider-a{position:absolute;left:0;top:0;width:100%;height:100%}
#slider-handle{position:absolute;top:0;bottom:0;width:2px;margin-left:-1px;background:#fff;box-shadow:0 0 3px #000;pointer-events:none}
.tag{position:absolute;top:8px;background:rgba(0,0,0,.6);color:#fff;padding:2px 6px;border-radius:3px;font-size:12px;line-height:1.3}
#slider-range{width:min(100%,1024px);display:block;margin-top:8px}
.crop img{display:block;border:1px solid var(--line)}
.cropcap{display:flex;font-size:12px;color:var(--muted)}
.cropcap span{flex:1;text-align:center}
.plots img{width:640px;max-width:100%;border:1px solid var(--line);background:#fff}
.groups{display:flex;flex-wrap:wrap;gap:10px 28px}
.group h3{font-size:14px;margin:6px 0}
.gallery img{max-width:200px;max-height:200px;display:block;border:1px solid var(--line);image-rendering:pixelated;background:#222}
pre{background:#f0f2f6;padding:8px;overflow:auto;font-size:12px}
#selftest{display:none}
"#;

/// The script.
pub const SCRIPT: &str = r#"
(function(){
const data=JSON.parse(document.getElementById('report-data').textContent);
const selA=document.getElementById('slider-left'),selB=document.getElementById('slider-right');
const imgA=document.getElementById('slider-a'),imgB=document.getElementById('slider-b');
const range=document.getElementById('slider-range'),handle=document.getElementById('slider-handle');
const box=document.getElementById('slider'),tagA=document.getElementById('tag-a'),tagB=document.getElementById('tag-b');
function setSplit(p){
  p=Math.max(0,Math.min(100,p));
  imgA.style.clipPath='inset(0 '+(100-p)+'% 0 0)';
  handle.style.left=p+'%';
  if(String(range.value)!==String(p))range.value=p;
}
function pick(sel,img,tag){const o=sel.options[sel.selectedIndex];img.src=o.value;tag.textContent=o.textContent;}
if(range){
  range.addEventListener('input',()=>setSplit(parseFloat(range.value)));
  selA.addEventListener('change',()=>pick(selA,imgA,tagA));
  selB.addEventListener('change',()=>pick(selB,imgB,tagB));
  let drag=false;
  const at=e=>{const r=box.getBoundingClientRect();setSplit((e.clientX-r.left)/r.width*100);};
  box.addEventListener('pointerdown',e=>{drag=true;if(box.setPointerCapture&&e.pointerId!==undefined){try{box.setPointerCapture(e.pointerId)}catch(_){}}at(e);});
  box.addEventListener('pointermove',e=>{if(drag)at(e);});
  window.addEventListener('pointerup',()=>{drag=false;});
  setSplit(parseFloat(range.value));
}
// Sortable metrics table: click a header; numbers sort by their data-v.
document.querySelectorAll('#metrics th').forEach((th,i)=>{
  th.addEventListener('click',()=>{
    const tb=document.querySelector('#metrics tbody.runs');
    const rows=[...tb.rows];const asc=th.dataset.dir!=='asc';th.dataset.dir=asc?'asc':'desc';
    rows.sort((a,b)=>{const x=a.cells[i].dataset.v,y=b.cells[i].dataset.v;
      const c=(x!==undefined&&y!==undefined)?parseFloat(x)-parseFloat(y):a.cells[i].textContent.localeCompare(b.cells[i].textContent);
      return asc?c:-c;});
    rows.forEach(r=>tb.appendChild(r));
  });
});
if(!/[?&]selftest=1\b/.test(location.search))return;
function run(){
  const out={};
  const rows=[...document.querySelectorAll('tr.technique-row')].map(r=>r.dataset.label);
  out.expected_rows=data.labels;
  out.missing_rows=data.labels.filter(l=>!rows.includes(l));
  const imgs=[...document.images];
  out.images=imgs.length;
  out.broken_images=imgs.filter(i=>!(i.complete&&i.naturalWidth>0)).map(i=>i.getAttribute('src'));
  out.plots=imgs.filter(i=>/\.svg$/.test(i.getAttribute('src')||'')).length;
  let moved=false,dragged=false,picked=false;
  if(range){
    range.value=20;range.dispatchEvent(new Event('input'));
    const c1=getComputedStyle(imgA).clipPath,h1=handle.getBoundingClientRect().left;
    range.value=80;range.dispatchEvent(new Event('input'));
    const c2=getComputedStyle(imgA).clipPath,h2=handle.getBoundingClientRect().left;
    moved=c1!==c2&&h2>h1;
    const r=box.getBoundingClientRect();
    const ev=(t,x)=>box.dispatchEvent(new PointerEvent(t,{bubbles:true,clientX:x,clientY:r.top+r.height/2,pointerId:1}));
    ev('pointerdown',r.left+r.width*0.3);ev('pointermove',r.left+r.width*0.6);window.dispatchEvent(new PointerEvent('pointerup',{}));
    dragged=Math.abs(parseFloat(range.value)-60)<1;
    if(selB.options.length>2){const before=imgB.getAttribute('src');selB.selectedIndex=2;selB.dispatchEvent(new Event('change'));picked=imgB.getAttribute('src')!==before;}else picked=true;
  }
  out.slider_moved=moved;out.slider_dragged=dragged;out.slider_picks=picked;
  out.ok=out.missing_rows.length===0&&out.broken_images.length===0&&moved&&dragged&&picked;
  const pre=document.getElementById('selftest');pre.textContent=JSON.stringify(out);pre.dataset.done='1';
}
if(document.readyState==='complete')run();else window.addEventListener('load',run);
})();
"#;
