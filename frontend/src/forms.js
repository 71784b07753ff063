// Form checks in the browser with the server's own bounds (the JSON schemas /api/config
// sends: FLConfig for runs, RecordingRequest for recordings), and server errors as
// sentences: a 422's field errors are named, never shown as raw JSON.

const LABELS = { min_clients: "minimum clients", fraction_fit: "fraction of clients", countdown_s: "countdown" };

export function fieldLabel(name) {
  return LABELS[name] ?? name.replaceAll("_", " ");
}

/** The problem with `raw` (an input's text) for a numeric field, as a sentence, or null. */
export function checkNumber(name, spec, raw) {
  const label = fieldLabel(name);
  const text = String(raw ?? "").trim();
  const integer = spec.type === "integer";
  const lo = spec.minimum ?? spec.exclusiveMinimum;
  const hi = spec.maximum ?? spec.exclusiveMaximum;
  const range =
    lo !== undefined && hi !== undefined
      ? ` from ${spec.exclusiveMinimum !== undefined ? `more than ${lo}` : lo} to ${hi}`
      : lo !== undefined
        ? ` of at least ${lo}`
        : hi !== undefined
          ? ` of at most ${hi}`
          : "";
  const want = `${label[0].toUpperCase()}${label.slice(1)} must be ${integer ? "a whole number" : "a number"}${range}`;
  if (!text) return `${want}; it is empty.`;
  const value = Number(text);
  if (!Number.isFinite(value)) return `${want}; "${text}" is not a number.`;
  if (integer && !Number.isInteger(value)) return `${want}; ${text} is not whole.`;
  if (spec.minimum !== undefined && value < spec.minimum) return `${want}; ${text} is too small.`;
  if (spec.exclusiveMinimum !== undefined && value <= spec.exclusiveMinimum) return `${want}; ${text} is too small.`;
  if (spec.maximum !== undefined && value > spec.maximum) {
    return name === "min_clients"
      ? `${want}: the federation has ${spec.maximum} drone${spec.maximum === 1 ? "" : "s"}, so ${text} can never be reached.`
      : `${want}; ${text} is too large.`;
  }
  if (spec.exclusiveMaximum !== undefined && value >= spec.exclusiveMaximum) return `${want}; ${text} is too large.`;
  return null;
}

/** An API error as sentences: each field error of a 422 named by its field. */
export function errorText(err) {
  const errors = err?.errors || [];
  if (err?.status === 422 && errors.length) {
    return errors
      .map((e) => {
        const field = [...(e.loc || [])].reverse().find((p) => typeof p === "string" && p !== "body");
        return `${field ? `${fieldLabel(field)}: ` : ""}${e.msg}.`;
      })
      .join(" ");
  }
  return err?.message ?? String(err);
}
