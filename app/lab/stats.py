"""Summary statistics of latency samples, shared by the benchmarks and the load tests."""

from __future__ import annotations


def percentiles_ms(values_ms: list[float]) -> dict:
    """`n`, nearest-rank `p50_ms` and `p99_ms`, and `max_ms` of latencies [ms], rounded to a microsecond;
    `{"n": 0}` when there are no samples."""
    if not values_ms:
        return {"n": 0}
    a = sorted(values_ms)
    return {"n": len(a), "p50_ms": round(a[len(a) // 2], 3), "p99_ms": round(a[min(len(a) - 1, int(0.99 * len(a)))], 3),
            "max_ms": round(a[-1], 3)}
