import { describe, expect, it } from "vitest";
import { formatSummary } from "../src/summary";

const base = {
  label: 1,
  axis: "z",
  traced_slices: 5,
  empty_slices: 1,
  seconds: 750.4,
  contour_seconds: 150,
  predicted_dice: 0.96249,
};

describe("tracing summary line", () => {
  it("shows slices, minutes and the predicted Dice", () => {
    expect(formatSummary(base)).toBe("5 traced slices, 1 empty · 12:30 min · predicted Dice 0.962");
  });
  it("says when there is no prediction yet", () => {
    expect(formatSummary({ ...base, traced_slices: 1, empty_slices: 0, seconds: 59.6, predicted_dice: null })).toBe(
      "1 traced slice · 1:00 min · predicted Dice after 3 drawn slices",
    );
  });
});
