// Camera moves on the scene's `camera` object (position, target, up):
// orbit turns the position around the target, pan moves both along the
// view plane, zoom scales the distance to the target.

const sub = (a, b) => a.map((v, i) => v - b[i]);
const add = (a, b) => a.map((v, i) => v + b[i]);
const scale = (a, s) => a.map((v) => v * s);
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const normalize = (a) => scale(a, 1 / Math.hypot(...a));

// Rotate v about the unit axis k by angle (radians), Rodrigues' formula.
function rotate(v, k, angle) {
  const c = Math.cos(angle), s = Math.sin(angle);
  return add(add(scale(v, c), scale(cross(k, v), s)), scale(k, dot(k, v) * (1 - c)));
}

// Orbit by dx, dy pixels (0.01 radian per pixel) around the target.
export function orbit(camera, dx, dy) {
  const up = normalize(camera.up ?? [0, 1, 0]);
  let offset = sub(camera.position, camera.target);
  offset = rotate(offset, up, -dx * 0.01);
  const right = normalize(cross(up, offset));
  const turned = rotate(offset, right, -dy * 0.01);
  // Stop short of the poles so the view never flips over the up vector.
  if (Math.abs(dot(normalize(turned), up)) < 0.98) offset = turned;
  camera.position = add(camera.target, offset);
}

// Pan by dx, dy pixels: both points move in the view plane, in proportion to the distance.
export function pan(camera, dx, dy, heightPixels) {
  const up = normalize(camera.up ?? [0, 1, 0]);
  const view = sub(camera.target, camera.position);
  const distance = Math.hypot(...view);
  const right = normalize(cross(view, up));
  const trueUp = normalize(cross(right, view));
  const fov = ((camera.fov_y ?? 40) * Math.PI) / 180;
  const perPixel = (2 * distance * Math.tan(fov / 2)) / heightPixels;
  const move = add(scale(right, -dx * perPixel), scale(trueUp, dy * perPixel));
  camera.position = add(camera.position, move);
  camera.target = add(camera.target, move);
}

// Zoom: the distance to the target times exp(amount).
export function zoom(camera, amount) {
  const offset = sub(camera.position, camera.target);
  camera.position = add(camera.target, scale(offset, Math.exp(amount)));
}
