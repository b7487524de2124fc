import { describe, expect, it } from "vitest";
import { formatMetric } from "../src/evalpanel";

describe("metric formatting", () => {
  it("formats ratios, counts, distances and volumes", () => {
    expect(formatMetric(0.91234567, "ratio", "µm")).toBe("0.9123");
    expect(formatMetric(1234567, "count", "µm")).toBe("1,234,567");
    expect(formatMetric(1.5, "dist", "µm")).toBe("1.500 µm");
    expect(formatMetric(12.34, "vol", "mm")).toBe("12.3 mm³");
    expect(formatMetric(null, "ratio", "mm")).toBe("—");
  });
});
