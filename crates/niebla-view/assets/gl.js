// WebGL2 display of linear HDR frames: two RGB16F textures (slot A, the
// scene's integrator; slot B, the split view's), tone-mapped in a fragment
// shader, so exposure and tone-curve changes need no re-render.
//   mode 0: A alone; 1: wipe (A left of the line, B right of it);
//   2: false-colour map of the relative difference |A - B| / (B + eps).

const VERTEX = `#version 300 es
out vec2 uv;
void main() {
  vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
  uv = vec2(p.x, 1.0 - p.y); // texture row 0 (the image's top row) at the top of the canvas
  gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}`;

const FRAGMENT = `#version 300 es
precision highp float;
in vec2 uv;
out vec4 color;
uniform sampler2D imageA;
uniform sampler2D imageB;
uniform int mode;
uniform int curve;
uniform float exposure;
uniform float wipe;
uniform float errorScale;
uniform float eps;

vec3 toneMap(vec3 c) {
  c *= exp2(exposure);
  if (curve == 1) c = c / (1.0 + c);                      // Reinhard
  if (curve == 2) c = clamp((c * (2.51 * c + 0.03)) / (c * (2.43 * c + 0.59) + 0.14), 0.0, 1.0); // ACES fit (Narkowicz 2015)
  c = clamp(c, 0.0, 1.0);
  return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c)); // sRGB
}

// A false-colour ramp (dark blue, cyan, yellow, red) for t in [0, 1].
vec3 ramp(float t) {
  t = clamp(t, 0.0, 1.0);
  vec3 a = vec3(0.05, 0.03, 0.35), b = vec3(0.0, 0.75, 0.85), c = vec3(0.98, 0.9, 0.1), d = vec3(0.85, 0.05, 0.05);
  return t < 0.33 ? mix(a, b, t / 0.33) : t < 0.66 ? mix(b, c, (t - 0.33) / 0.33) : mix(c, d, (t - 0.66) / 0.34);
}

void main() {
  vec3 a = texture(imageA, uv).rgb;
  if (mode == 1) {
    vec3 b = texture(imageB, uv).rgb;
    if (abs(uv.x - wipe) < 0.002) { color = vec4(1.0, 1.0, 1.0, 1.0); return; }
    color = vec4(toneMap(uv.x < wipe ? a : b), 1.0);
  } else if (mode == 2) {
    vec3 b = texture(imageB, uv).rgb;
    float e = length(a - b) / (length(b) + eps);
    color = vec4(ramp(e * errorScale), 1.0);
  } else {
    color = vec4(toneMap(a), 1.0);
  }
}`;

function compile(gl, type, source) {
  const shader = gl.createShader(type);
  gl.shaderSource(shader, source);
  gl.compileShader(shader);
  if (!gl.getShaderParameter(shader, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(shader));
  return shader;
}

export class Display {
  constructor(canvas) {
    const gl = canvas.getContext('webgl2', { preserveDrawingBuffer: true });
    if (!gl) throw new Error('this browser has no WebGL2');
    this.gl = gl;
    this.canvas = canvas;
    const program = gl.createProgram();
    gl.attachShader(program, compile(gl, gl.VERTEX_SHADER, VERTEX));
    gl.attachShader(program, compile(gl, gl.FRAGMENT_SHADER, FRAGMENT));
    gl.linkProgram(program);
    if (!gl.getProgramParameter(program, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(program));
    this.program = program;
    this.textures = [this.makeTexture(), this.makeTexture()];
    this.settings = { mode: 0, curve: 0, exposure: 0, wipe: 0.5, errorScale: 4, eps: 1e-3 };
  }

  makeTexture() {
    const gl = this.gl;
    const texture = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, texture);
    for (const [k, v] of [[gl.TEXTURE_MIN_FILTER, gl.NEAREST], [gl.TEXTURE_MAG_FILTER, gl.NEAREST],
      [gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE], [gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE]]) gl.texParameteri(gl.TEXTURE_2D, k, v);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGB16F, 1, 1, 0, gl.RGB, gl.HALF_FLOAT, new Uint16Array(3));
    return texture;
  }

  // Upload slot `index`'s frame: `halves` holds R, G, B binary16 values per pixel, rows from the top.
  upload(index, width, height, halves) {
    const gl = this.gl;
    gl.bindTexture(gl.TEXTURE_2D, this.textures[index]);
    gl.pixelStorei(gl.UNPACK_ALIGNMENT, 2);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGB16F, width, height, 0, gl.RGB, gl.HALF_FLOAT, halves);
  }

  draw() {
    const gl = this.gl, s = this.settings;
    gl.viewport(0, 0, this.canvas.width, this.canvas.height);
    gl.useProgram(this.program);
    gl.activeTexture(gl.TEXTURE0);
    gl.bindTexture(gl.TEXTURE_2D, this.textures[0]);
    gl.activeTexture(gl.TEXTURE1);
    gl.bindTexture(gl.TEXTURE_2D, this.textures[1]);
    const u = (name) => gl.getUniformLocation(this.program, name);
    gl.uniform1i(u('imageA'), 0);
    gl.uniform1i(u('imageB'), 1);
    gl.uniform1i(u('mode'), s.mode);
    gl.uniform1i(u('curve'), s.curve);
    gl.uniform1f(u('exposure'), s.exposure);
    gl.uniform1f(u('wipe'), s.wipe);
    gl.uniform1f(u('errorScale'), s.errorScale);
    gl.uniform1f(u('eps'), s.eps);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
  }
}

// binary16 to number.
export function halfToFloat(h) {
  const sign = h & 0x8000 ? -1 : 1, exponent = (h >> 10) & 0x1f, fraction = h & 0x3ff;
  if (exponent === 0) return sign * fraction * 2 ** -24;
  if (exponent === 31) return fraction ? NaN : sign * Infinity;
  return sign * (1 + fraction / 1024) * 2 ** (exponent - 15);
}
