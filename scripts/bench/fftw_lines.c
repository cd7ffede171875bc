/* FFTW on the lines of solvers/fluid/benches/transforms.rs: every line along
 * x, then along y, of an n^3 array (x fastest), forward and backward, real
 * FFT in halfcomplex order (R2HC/HC2R) and DCT-II/III (REDFT10/REDFT01), one
 * guru plan per axis and direction (FFTW_MEASURE), single thread. Prints the
 * median ns per value per transform. Build: cc -O2 fftw_lines.c -lfftw3 -lm */
#include <fftw3.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

static int compare(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static fftw_plan plan_lines(int n, int axis, fftw_r2r_kind kind, double *data) {
    /* One line of n values with stride `stride`; the other two axes batched. */
    fftw_iodim64 line, batch[2];
    ptrdiff_t stride = axis == 0 ? 1 : n;
    line.n = n; line.is = stride; line.os = stride;
    if (axis == 0) {
        batch[0].n = n; batch[0].is = n; batch[0].os = n;           /* y */
    } else {
        batch[0].n = n; batch[0].is = 1; batch[0].os = 1;           /* x */
    }
    batch[1].n = n; batch[1].is = (ptrdiff_t)n * n; batch[1].os = (ptrdiff_t)n * n; /* z */
    return fftw_plan_guru64_r2r(1, &line, 2, batch, data, data, &kind, FFTW_MEASURE);
}

int main(void) {
    int sizes[2] = {64, 128};
    const char *names[2] = {"Periodic", "Neumann"};
    fftw_r2r_kind forward[2] = {FFTW_R2HC, FFTW_REDFT10};
    fftw_r2r_kind backward[2] = {FFTW_HC2R, FFTW_REDFT01};
    for (int s = 0; s < 2; s++) {
        int n = sizes[s];
        size_t values = (size_t)n * n * n;
        double *data = fftw_malloc(sizeof(double) * values);
        for (int kind = 0; kind < 2; kind++) {
            for (int axis = 0; axis < 2; axis++) {
                fftw_plan f = plan_lines(n, axis, forward[kind], data);
                fftw_plan b = plan_lines(n, axis, backward[kind], data);
                for (size_t k = 0; k < values; k++) data[k] = (double)((k * 7919) % 1013);
                int repeats = n == 64 ? 21 : 7;
                double samples[21];
                for (int r = 0; r < repeats; r++) {
                    double started = now();
                    fftw_execute(f);
                    fftw_execute(b);
                    samples[r] = (now() - started) * 1e9 / (2.0 * values);
                }
                qsort(samples, repeats, sizeof(double), compare);
                printf("fftw n=%d kind=%s axis=%d ns_per_value=%.3f\n", n, names[kind], axis,
                       samples[repeats / 2]);
                fftw_destroy_plan(f);
                fftw_destroy_plan(b);
            }
        }
        fftw_free(data);
    }
    return 0;
}
