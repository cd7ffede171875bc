/* Round trip of a cache line between two threads, in ns: the probe that
 * tells whether this machine's two CPUs share a last-level cache right now.
 *
 * Two threads bounce a counter through one atomic. On cores that share a
 * cache (one die) a round trip takes about 100 ns; across dies, or across
 * virtual CPUs that the host placed on two dies, about 400 ns. The DEM's
 * two threads share the grains at the boundary between their runs every
 * step, so their gain follows this figure (docs/performance.md).
 *
 * cc -O2 -pthread core_latency.c -o core_latency && ./core_latency */
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <time.h>

#define ROUND_TRIPS 200000L

static _Atomic long counter __attribute__((aligned(64)));

static void *answer(void *unused) {
    (void)unused;
    for (long k = 0; k < ROUND_TRIPS; k++) {
        while (atomic_load_explicit(&counter, memory_order_acquire) != 2 * k + 1)
            ;
        atomic_store_explicit(&counter, 2 * k + 2, memory_order_release);
    }
    return NULL;
}

int main(void) {
    pthread_t other;
    struct timespec start, end;
    pthread_create(&other, NULL, answer, NULL);
    clock_gettime(CLOCK_MONOTONIC, &start);
    for (long k = 0; k < ROUND_TRIPS; k++) {
        atomic_store_explicit(&counter, 2 * k + 1, memory_order_release);
        while (atomic_load_explicit(&counter, memory_order_acquire) != 2 * k + 2)
            ;
    }
    clock_gettime(CLOCK_MONOTONIC, &end);
    pthread_join(other, NULL);
    double ns = (end.tv_sec - start.tv_sec) * 1e9 + (end.tv_nsec - start.tv_nsec);
    printf("%.1f\n", ns / ROUND_TRIPS);
    return 0;
}
