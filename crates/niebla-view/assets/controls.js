// Editors for the scene's media and lights: one slider (with a number box)
// per numeric field, three per RGB or XYZ triple, found by walking the
// scene JSON. A slider being dragged reports interactive edits; letting go
// or typing a number reports a final edit. Each input carries
// data-path="media.NAME.FIELD" (the JSON path it edits).

const SKIP = new Set(['type', 'density', 'to_world', 'storage', 'majorant_resolution', 'bounds', 'data', 'dims',
  'shape', 'file', 'two_sided', 'grid', 'column']);

function range(key, value) {
  if (key === 'g') return [-0.99, 0.99];
  if (key === 'albedo') return [0, 1];
  if (key === 'cutoff_angle' || key === 'beam_width') return [0, 90];
  if (['position', 'direction', 'target', 'center'].includes(key)) {
    const m = Math.max(10, 2 * Math.abs(value));
    return [-m, m];
  }
  return [0, Math.max(4 * Math.abs(value), 1)];
}

function slider(parent, label, path, value, key, set, onEdit) {
  const [min, max] = range(key, value);
  const row = document.createElement('label');
  row.className = 'slider';
  const name = document.createElement('span');
  name.textContent = label;
  const input = document.createElement('input');
  Object.assign(input, { type: 'range', min, max, step: (max - min) / 1000, value });
  input.dataset.path = path;
  const number = document.createElement('input');
  Object.assign(number, { type: 'number', step: 'any', value });
  number.dataset.path = path + '#number';
  input.addEventListener('input', () => { number.value = input.value; set(Number(input.value)); onEdit(true); });
  input.addEventListener('change', () => { set(Number(input.value)); onEdit(false); });
  number.addEventListener('change', () => { input.value = number.value; set(Number(number.value)); onEdit(false); });
  row.append(name, input, number);
  parent.append(row);
}

// Sliders for the numeric fields of `object` (recursing into objects).
function fields(parent, object, path, onEdit) {
  for (const [key, value] of Object.entries(object)) {
    if (SKIP.has(key)) continue;
    const here = `${path}.${key}`;
    if (typeof value === 'number') {
      slider(parent, key, here, value, key, (v) => { object[key] = v; }, onEdit);
    } else if (Array.isArray(value) && value.length === 3 && value.every((v) => typeof v === 'number')) {
      const names = ['position', 'direction', 'target', 'center'].includes(key) ? 'xyz' : 'rgb';
      value.forEach((v, i) => slider(parent, `${key}.${names[i]}`, `${here}[${i}]`, v, key, (x) => { value[i] = x; }, onEdit));
    } else if (value && typeof value === 'object' && !Array.isArray(value)) {
      fields(parent, value, here, onEdit);
    }
  }
}

function group(parent, title) {
  const box = document.createElement('fieldset');
  const legend = document.createElement('legend');
  legend.textContent = title;
  box.append(legend);
  parent.append(box);
  return box;
}

// Fill `container` with editors of `scene`'s media and lights; `onEdit(interactive)` after each change.
export function buildSceneControls(container, scene, onEdit) {
  container.replaceChildren();
  for (const [name, medium] of Object.entries(scene.media ?? {})) {
    if (!('scale' in medium)) medium.scale = 1; // the density scale (the parser's default)
    fields(group(container, `medium ${name}`), medium, `media.${name}`, onEdit);
  }
  (scene.lights ?? []).forEach((light, i) => fields(group(container, `light ${i}: ${light.type}`), light, `lights[${i}]`, onEdit));
}
