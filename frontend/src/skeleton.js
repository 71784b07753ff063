// @ts-check
// Drawing MediaPipe's 33-landmark BlazePose skeleton on a canvas. Landmarks are in
// normalised image coordinates (x right, y down, 0..1, may leave the image).

export const CONNECTIONS = [
  [0, 1], [1, 2], [2, 3], [3, 7], [0, 4], [4, 5], [5, 6], [6, 8], [9, 10],
  [11, 12], [11, 13], [13, 15], [15, 17], [15, 19], [15, 21], [17, 19],
  [12, 14], [14, 16], [16, 18], [16, 20], [16, 22], [18, 20],
  [11, 23], [12, 24], [23, 24], [23, 25], [24, 26], [25, 27], [26, 28],
  [27, 29], [28, 30], [29, 31], [30, 32], [27, 31], [28, 32],
];
// The operator's left side (odd indices above 10) and right side in two colours.
const LEFT = new Set([11, 13, 15, 17, 19, 21, 23, 25, 27, 29, 31]);

/**
 * @param {CanvasRenderingContext2D} ctx
 * @param {number[][]} xyz 33 landmarks [x, y, z]
 * @param {number[] | null} visibility 33 values in [0, 1], or none (all drawn as seen)
 * @param {number} w
 * @param {number} h
 */
export function drawSkeleton(ctx, xyz, visibility, w, h, { alpha = 1 } = {}) {
  if (!xyz || xyz.length !== 33) return;
  ctx.save();
  ctx.globalAlpha = alpha;
  ctx.lineWidth = Math.max(2, w / 160);
  for (const [a, b] of CONNECTIONS) {
    const va = visibility ? visibility[a] : 1;
    const vb = visibility ? visibility[b] : 1;
    ctx.strokeStyle = LEFT.has(a) && LEFT.has(b) ? "#4fc3f7" : LEFT.has(a) || LEFT.has(b) ? "#e0e0e0" : "#ffb74d";
    ctx.globalAlpha = alpha * (Math.min(va, vb) < 0.5 ? 0.35 : 1);
    ctx.beginPath();
    ctx.moveTo(xyz[a][0] * w, xyz[a][1] * h);
    ctx.lineTo(xyz[b][0] * w, xyz[b][1] * h);
    ctx.stroke();
  }
  ctx.fillStyle = "#ffffff";
  for (let i = 0; i < 33; i++) {
    ctx.globalAlpha = alpha * ((visibility ? visibility[i] : 1) < 0.5 ? 0.35 : 1);
    ctx.beginPath();
    ctx.arc(xyz[i][0] * w, xyz[i][1] * h, Math.max(2, w / 200), 0, 2 * Math.PI);
    ctx.fill();
  }
  ctx.restore();
}

/** @param {CanvasRenderingContext2D} ctx @param {number} w @param {number} h */
export function clear(ctx, w, h) {
  ctx.fillStyle = "#101418";
  ctx.fillRect(0, 0, w, h);
}
