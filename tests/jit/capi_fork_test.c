/* capi_fork_test.c: a host that forks while the library's tier-up thread may
 * be compiling (Python's multiprocessing does this), through the C API.
 *
 * For fork delays of 0, 1, ..., 12 ms after a tiered compile (the default
 * codegen; cache=off so that every compile tiers up), the child samples and
 * evaluates the parent's kernel, compiles new kernels (tiered, and optimized,
 * whose code generator is the one the tier-up thread uses) and evaluates
 * them. A child that deadlocks is killed by its alarm after 20 s and fails
 * the test, as does any wrong value or a nonzero exit. The parent's kernels
 * keep working after every fork. */
#define _POSIX_C_SOURCE 200809L
#include <facet/facet.h>

#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

static const char* kMaterial =
    "material coat { input r = 0.4 in 0 .. 1; ndf = ggx(r * r); masking = smith_height_correlated;\n"
    "  fresnel = dielectric(eta = 1.5); diffuse = lambert(rgb(0.3, 0.2, 0.1)); }\n"
    "material metal { ndf = beckmann(0.3); masking = smith_separable;\n"
    "  fresnel = conductor(eta = rgb(0.2, 0.9, 1.1), k = rgb(3.9, 2.4, 2.1)); }\n";

static facet_kernel* compile(const char* material, const char* options) {
    char err[512];
    facet_kernel* k = facet_compile_text(kMaterial, "fork.mat", material, options, err, sizeof err);
    if (!k) fprintf(stderr, "compile %s (%s): %s\n", material, options, err);
    return k;
}

/* f at a fixed pair and one sample: 0 when both look right. */
static int exercise(const facet_kernel* k, float expected_f) {
    const float wi[3] = {0.0f, 0.6f, 0.8f}, wo[3] = {0.0f, -0.6f, 0.8f}, u[3] = {0.3f, 0.4f, 0.7f};
    float rgb[3], wis[3], pdf = 0, weight[3];
    facet_eval(k, wi, wo, NULL, rgb);
    if (!(rgb[0] > 0) || (expected_f > 0 && fabsf(rgb[0] - expected_f) > 1e-6f * expected_f)) {
        fprintf(stderr, "f = %g, expected %g\n", rgb[0], expected_f);
        return 1;
    }
    if (facet_sample(k, wo, u, NULL, wis, &pdf, weight) != 0 || !(pdf > 0)) {
        fprintf(stderr, "sample: pdf %g\n", pdf);
        return 1;
    }
    return 0;
}

static float f_of(const facet_kernel* k) {
    const float wi[3] = {0.0f, 0.6f, 0.8f}, wo[3] = {0.0f, -0.6f, 0.8f};
    float rgb[3];
    facet_eval(k, wi, wo, NULL, rgb);
    return rgb[0];
}

static int child(facet_kernel* parents, float expected) {
    alarm(20);
    if (exercise(parents, expected)) return 2;
    facet_kernel* tiered = compile("metal", "cache=off");
    facet_kernel* optimized = compile("coat", "cache=off;codegen=optimized;set.r=0.7");
    if (!tiered || !optimized) return 3;
    if (exercise(tiered, 0) || exercise(optimized, 0)) return 4;
    facet_release(tiered);
    facet_release(optimized);
    facet_release(parents);
    return 0;
}

int main(void) {
    facet_kernel* reference = compile("coat", "cache=off;codegen=optimized");
    if (!reference) return 1;
    const float expected = f_of(reference);
    int failures = 0, runs = 0;
    for (int step = 0; step <= 12; ++step) {
        facet_kernel* k = compile("coat", "cache=off");
        if (!k) return 1;
        struct timespec delay = {0, (long)step * 1000000L}; /* 0 .. 12 ms */
        nanosleep(&delay, NULL);
        fflush(NULL);
        pid_t pid = fork();
        if (pid < 0) {
            perror("fork");
            return 1;
        }
        if (pid == 0) _exit(child(k, expected));
        int status = 0;
        if (waitpid(pid, &status, 0) != pid) {
            perror("waitpid");
            return 1;
        }
        ++runs;
        if (WIFSIGNALED(status)) {
            fprintf(stderr, "FAIL: fork after %.1f ms: child killed by signal %d%s\n", (double)step, WTERMSIG(status),
                    WTERMSIG(status) == SIGALRM ? " (it hung)" : "");
            ++failures;
        } else if (WEXITSTATUS(status) != 0) {
            fprintf(stderr, "FAIL: fork after %.1f ms: child exited %d\n", (double)step, WEXITSTATUS(status));
            ++failures;
        }
        if (exercise(k, expected)) {
            fprintf(stderr, "FAIL: the parent's kernel after fork %d\n", step);
            ++failures;
        }
        facet_release(k);
    }
    facet_release(reference);
    printf("%d forks, %d failed\n", runs, failures);
    return failures ? 1 : 0;
}
