/* ehservo_run.c: a scenario's closed loop stepped from C through the C ABI
 * of crates/ehservo-ffi (include/ehservo.h), the loop owned by this file.
 *
 *   ehservo_run SCENARIO.toml            step the loop to its horizon and
 *                                        print e_max_deg as `ehservo run`'s
 *                                        summary.json has it
 *   ehservo_run SCENARIO.toml --controller
 *                                        also step the scenario's controller
 *                                        alone, fed the loop's measurements,
 *                                        and check that its command is the
 *                                        loop's, bit for bit, every sample
 *                                        (a scenario with exact sensors)
 *   ehservo_run --misuse SCENARIO.toml   the errors of calls made wrong (a
 *                                        null handle, NaN arguments), one
 *                                        line each
 *
 * A scenario that does not load prints `error: ` and the message
 * `ehservo run` prints, and exits with 2.
 *
 * Build (after cargo build -p ehservo-ffi), from the repository's root:
 *   gcc -std=c11 -Wall -Wextra -O2 -I crates/ehservo-ffi/include \
 *       examples/c/ehservo_run.c -L target/debug -lehservo_ffi \
 *       -Wl,-rpath,"$PWD/target/debug" -o ehservo_run
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "ehservo.h"

static int fail(EhservoStatus st, const char *what) {
    fprintf(stderr, "error: %s\n", ehservo_last_error());
    (void)what;
    return st == EHSERVO_STATUS_SCENARIO ? 2 : 1;
}

static int misuse(const char *path) {
    EhservoSample s;
    double u = 0.0;
    const double x[3] = {0.0, 0.0, 0.0};
    EhservoController *ctl = NULL;
    EhservoStatus st;

    /* A step on a loop that was never made. */
    st = ehservo_sim_step(NULL, &s);
    printf("null sim: status %d: %s\n", (int)st, ehservo_last_error());
    st = ehservo_controller_step(NULL, 0.0, x, NULL, &u);
    printf("null controller: status %d: %s\n", (int)st, ehservo_last_error());

    st = ehservo_controller_new(path, &ctl);
    if (st != EHSERVO_STATUS_OK) return fail(st, "ehservo_controller_new");
    st = ehservo_controller_step(ctl, NAN, x, NULL, &u);
    printf("NaN t: status %d: %s\n", (int)st, ehservo_last_error());
    const double bad[3] = {NAN, 0.0, 0.0};
    st = ehservo_controller_step(ctl, 0.0, bad, NULL, &u);
    printf("NaN x: status %d: u = %g: %s\n", (int)st, u, ehservo_last_error());
    ehservo_controller_free(ctl);
    return 0;
}

int main(int argc, char **argv) {
    if (argc >= 3 && strcmp(argv[1], "--misuse") == 0) return misuse(argv[2]);
    if (argc < 2 || argc > 3 || (argc == 3 && strcmp(argv[2], "--controller") != 0)) {
        fprintf(stderr, "usage: %s SCENARIO.toml [--controller] | --misuse SCENARIO.toml\n", argv[0]);
        return 2;
    }
    const char *path = argv[1];
    int check_controller = argc == 3;

    EhservoSim *sim = NULL;
    EhservoStatus st = ehservo_sim_new(path, &sim);
    if (st != EHSERVO_STATUS_OK) return fail(st, "ehservo_sim_new");

    EhservoController *ctl = NULL;
    if (check_controller) {
        st = ehservo_controller_new(path, &ctl);
        if (st != EHSERVO_STATUS_OK) {
            ehservo_sim_free(sim);
            return fail(st, "ehservo_controller_new");
        }
    }

    double period = 0.0;
    uint64_t steps = 0;
    ehservo_sim_info(sim, &period, &steps);

    /* The loop: one sample per call, to the horizon. */
    EhservoSample s;
    uint64_t samples = 0, mismatches = 0, saturated = 0;
    while ((st = ehservo_sim_step(sim, &s)) == EHSERVO_STATUS_OK) {
        samples++;
        /* A flag is tested by its constant (docs/flags.md), never by a
           bit number written by hand. */
        if (s.flags & EHSERVO_FLAG_SATURATED) saturated++;
        if (ctl) {
            const double x[3] = {s.theta, s.theta_dot, s.theta_ddot};
            double u = NAN;
            EhservoStatus cs = ehservo_controller_step(ctl, s.t, x, NULL, &u);
            if (cs != EHSERVO_STATUS_OK || memcmp(&u, &s.u, sizeof u) != 0) {
                if (mismatches++ < 5)
                    fprintf(stderr, "k = %llu: controller u = %.17g (status %d), loop u = %.17g\n",
                            (unsigned long long)s.k, u, (int)cs, s.u);
            }
        }
    }
    if (st != EHSERVO_STATUS_STOPPED) {
        ehservo_controller_free(ctl);
        ehservo_sim_free(sim);
        return fail(st, "ehservo_sim_step");
    }
    printf("%s\n", ehservo_last_error()); /* why it stopped */
    printf("samples=%llu period=%.17g steps=%llu\n", (unsigned long long)samples, period,
           (unsigned long long)steps);
    printf("saturated_samples=%llu\n", (unsigned long long)saturated);

    double e_max = NAN;
    st = ehservo_sim_e_max_deg(sim, &e_max);
    if (st == EHSERVO_STATUS_OK)
        printf("e_max_deg=%.17g\n", e_max);
    else
        printf("e_max_deg undefined: %s\n", ehservo_last_error());
    if (ctl) {
        printf("controller: %llu of %llu commands differ from the loop's\n",
               (unsigned long long)mismatches, (unsigned long long)samples);
        ehservo_controller_free(ctl);
    }
    ehservo_sim_free(sim);
    return mismatches == 0 ? 0 : 1;
}
