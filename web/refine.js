// ConeLOD web viewer — view-dependent refinement of a .clod file's cluster DAG.
//
// The JavaScript twin of vcg_ext/conelod/lod/lod_refine.cpp with its default order (the group's
// error projected on the screen, LodPriority::ScreenError), the same rules and the same order of
// expansions: the cut starts at the roots; a group is expanded (its simplified clusters replaced
// by its own clusters) only when all of them are in the cut, so that every cut is watertight;
// a drawn node above the pixel error whose group waits on others has those expanded first
// (demand); back-facing nodes (the three-state normal-cone test, perspective) are flagged culled
// and their groups come after every other; the refinement stops at the first group whose
// expansion does not fit the face budget. What differs is only that reading is asynchronous:
// each expansion awaits its children's records and their unit's geometry (one range each), and
// the next groups in the queue are read ahead while it waits.

const IN_CUT = 1, REFINED = 2;
const READ_AHEAD = 16;  // groups near the top of the queue read while an expansion waits

function sub(a, b) { return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]; }
function dot(a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
function norm(a) { return Math.sqrt(dot(a, a)); }

// A node's error projected on the screen at the nearest point of its bounding sphere (pixels).
export function projectedError(n, view) {
  const d = Math.max(norm(sub(view.eye, n.center)) - n.radius, 1e-9 * (1 + norm(n.center)));
  return (n.error / d) * (view.projectionScale > 0 ? view.projectionScale : 1);
}

// ClassifyPerspective (normal_cone.cpp): 'back', 'partial' or 'front'.
export function classifyPerspective(n, eye) {
  if (n.coneEmpty) return 'back';
  if (!(n.coneHalfAngle < Math.PI / 2)) return 'partial';
  const toEye = sub(eye, n.center), d = norm(toEye);
  if (d <= n.radius) return 'partial';
  const widen = Math.asin(n.radius / d);
  const a = Math.acos(Math.max(-1, Math.min(1, dot(n.coneAxis, toEye) / d)));
  if (a - n.coneHalfAngle - widen > Math.PI / 2) return 'back';
  if (a + n.coneHalfAngle + widen < Math.PI / 2) return 'front';
  return 'partial';
}

// std::priority_queue of QueueItem: visible before culled, larger priority first, lower key first.
function before(a, b) {
  if (a.culled !== b.culled) return a.culled < b.culled;
  if (a.priority !== b.priority) return a.priority > b.priority;
  return a.key < b.key;
}
class Heap {
  constructor() { this.a = []; }
  get size() { return this.a.length; }
  push(x) {
    const a = this.a;
    a.push(x);
    for (let i = a.length - 1; i > 0;) {
      const p = (i - 1) >> 1;
      if (!before(a[i], a[p])) break;
      [a[i], a[p]] = [a[p], a[i]];
      i = p;
    }
  }
  pop() {
    const a = this.a, top = a[0], last = a.pop();
    if (a.length) {
      a[0] = last;
      for (let i = 0; ;) {
        const l = 2 * i + 1, r = l + 1;
        let m = i;
        if (l < a.length && before(a[l], a[m])) m = l;
        if (r < a.length && before(a[r], a[m])) m = r;
        if (m === i) break;
        [a[i], a[m]] = [a[m], a[i]];
        i = m;
      }
    }
    return top;
  }
}

// view: { eye: [x, y, z], faceBudget, cullBackFacing, projectionScale, maxPixelError }.
// The cut: `cut` (node id -> culled flag), `faces`, `drawnFaces`, `budgetReached`.
export class Refiner {
  constructor(reader) {
    this.reader = reader;
    this.generation = 0;
  }

  async start(view) {
    const r = this.reader;
    this.view = view;
    this.generation++;
    this.state = new Uint8Array(r.info.nodeCount);
    this.cut = new Map();
    this.present = new Map();
    this.demand = new Map();
    this.queue = new Heap();
    this.faces = 0;
    this.drawnFaces = 0;
    this.refinements = 0;
    this.budgetReached = false;
    this.stopped = false;
    for (const id of r.roots) await this.addToCut(id);
  }

  done() { return this.stopped || this.queue.size === 0; }

  culledNode(n) { return this.view.cullBackFacing && classifyPerspective(n, this.view.eye) === 'back'; }

  pixelStop() { return this.view.projectionScale > 0 && this.view.maxPixelError > 0; }

  priorityOf(siblings) {
    const r = this.reader, view = this.view;
    let p = 0;
    for (const s of siblings) p = Math.max(p, projectedError(r.node(s), view));
    if (view.cullBackFacing) {
      let facing = 0;
      for (const s of siblings) {
        const n = r.node(s), toEye = sub(view.eye, n.center), len = norm(toEye);
        if (n.coneEmpty || !(len > 0)) {
          facing = 1;
          break;
        }
        const a = Math.acos(Math.max(-1, Math.min(1, dot(toEye, n.coneAxis) / len)));
        facing = Math.max(facing, Math.cos(Math.min(Math.PI / 2, Math.max(0, a - n.coneHalfAngle))));
      }
      p *= 0.25 + 0.75 * facing;
    }
    return p;
  }

  needOf(siblings) {
    let need = 0;
    for (const s of siblings) if (!this.cut.get(s)) need = Math.max(need, projectedError(this.reader.node(s), this.view));
    return need;
  }

  async demandGroup(clusters, need) {
    const key = Math.min(...clusters);
    const had = this.demand.get(key);
    if (had !== undefined && had >= need) return;
    this.demand.set(key, need);
    let complete = true;
    for (const s of clusters) {
      if (s >= this.state.length) throw new Error(`corrupt file: no node ${s}`);
      if (this.state[s] === IN_CUT) continue;
      complete = false;
      if (this.state[s] !== 0) return;  // its group was expanded: nothing to wait for
      await this.reader.loadNode(s);
      const parents = this.reader.node(s).parents;
      if (!parents.length) continue;
      await this.demandGroup(parents, need);
    }
    if (complete) this.queue.push({ culled: 0, priority: need, need, key });
  }

  async addToCut(id) {
    const n = this.reader.node(id);
    const culled = this.culledNode(n);
    this.state[id] = IN_CUT;
    this.cut.set(id, culled);
    this.faces += n.faceCount;
    if (!culled) this.drawnFaces += n.faceCount;
    if (!n.children.length) return;
    const key = Math.min(...n.siblings);
    const count = (this.present.get(key) || 0) + 1;
    this.present.set(key, count);
    if (count === n.siblings.length) {
      let allCulled = this.view.cullBackFacing;
      for (const s of n.siblings) {
        if (this.state[s] !== IN_CUT) throw new Error(`corrupt file: node ${id}'s siblings disagree`);
        if (!this.cut.get(s)) allCulled = false;
      }
      let priority = this.priorityOf(n.siblings), need = this.needOf(n.siblings);
      const d = this.demand.get(key);
      if (d !== undefined) {
        allCulled = false;
        need = Math.max(need, d);
        priority = Math.max(priority, d);
      }
      this.queue.push({ culled: allCulled ? 1 : 0, priority, need, key });
    } else if (!culled) {
      const need = projectedError(n, this.view);
      if (need > (this.pixelStop() ? this.view.maxPixelError : 0)) await this.demandGroup(n.siblings, need);
    }
  }

  removeFromCut(id) {
    const n = this.reader.node(id);
    if (!this.cut.get(id)) this.drawnFaces -= n.faceCount;
    this.faces -= n.faceCount;
    this.cut.delete(id);
    this.state[id] = REFINED;
  }

  // Reads what expanding group `key` needs: its children's records and their unit.
  async fetchGroup(key) {
    const r = this.reader;
    await r.loadChildren(key);
    const ch = r.node(key).children;
    if (ch.length) await r.loadUnit(ch[0]);
  }

  async expand(key) {
    const r = this.reader;
    if (this.stopped || this.state[key] !== IN_CUT) return;
    const kn = r.node(key), siblings = kn.siblings, children = kn.children;
    if (!children.length) return;
    for (const s of siblings) {
      const sn = r.node(s);
      if (s >= this.state.length || this.state[s] !== IN_CUT || sn.children.join() !== children.join() ||
          sn.siblings.join() !== siblings.join())
        throw new Error(`corrupt file: the clusters made from one group disagree (node ${s})`);
    }
    await this.fetchGroup(key);
    let removed = 0, added = 0;
    for (const s of siblings) removed += r.node(s).faceCount;
    for (const c of children) {
      if (c >= this.state.length || this.state[c] !== 0) throw new Error(`corrupt file: node ${c} is the child of two groups`);
      added += r.node(c).faceCount;
    }
    if (this.faces - removed + added > this.view.faceBudget) {
      this.budgetReached = true;
      this.stopped = true;
      return;
    }
    for (const s of siblings) this.removeFromCut(s);
    this.present.delete(key);
    for (const c of children) await this.addToCut(c);
    ++this.refinements;
  }

  // Up to maxRefinements expansions; reads ahead the next groups of the queue.
  async step(maxRefinements) {
    let done = 0;
    const pixelStop = this.pixelStop(), gen = this.generation;
    while (done < maxRefinements && !this.stopped && this.queue.size) {
      const top = this.queue.pop();
      if (pixelStop && (top.culled || top.need <= this.view.maxPixelError)) continue;
      // Read ahead: the groups near the top of the queue, while this one is read.
      for (let i = 0; i < Math.min(READ_AHEAD, this.queue.size); ++i) {
        const q = this.queue.a[i];
        if (!(pixelStop && (q.culled || q.need <= this.view.maxPixelError))) this.fetchGroup(q.key).catch(() => {});
      }
      const beforeCount = this.refinements;
      await this.expand(top.key);
      if (gen !== this.generation) return;  // restarted meanwhile
      done += this.refinements - beforeCount;
    }
  }
}
