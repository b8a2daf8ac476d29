-- wrk report: one line with the latency percentiles in milliseconds and the error count.
done = function(summary, latency, requests)
  local e = summary.errors
  io.write(string.format("p50=%.1f p95=%.1f p99=%.1f max=%.1f requests=%d errors=%d\n",
    latency:percentile(50) / 1000, latency:percentile(95) / 1000, latency:percentile(99) / 1000,
    latency.max / 1000, summary.requests, e.connect + e.read + e.write + e.status + e.timeout))
end
