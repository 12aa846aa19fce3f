/* Child processes for flexmbs_core_processes: start one with
 * posix_spawnp (no shell: the arguments go as they are), wait for any of a
 * set to end, send one a signal, and this program's own path.
 *
 * A child starts with SIGINT and SIGTERM at their default action and an
 * empty signal mask, standard input from /dev/null, and optionally in a
 * process group of its own: then a Ctrl-C at the terminal reaches the
 * parent only, which passes it on once to each child (a second SIGINT
 * would end a flexmbs child at once, see signals_shim.c). */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

extern char **environ;
int flexmbs_signals_caught(void);

/* Start `nargs` arguments packed in `args` (each ended by a NUL); the
 * program args[0] is searched in PATH. Standard output goes to the file
 * `out` (created or emptied) unless it is "", standard error to `err`, or
 * with the output when `err` is "". Returns the child's id, or -errno. */
int flexmbs_process_spawn(const char *args, int nargs, const char *out, const char *err,
                          int own_group)
{
    char **argv;
    const char *p = args;
    posix_spawn_file_actions_t actions;
    posix_spawnattr_t attr;
    sigset_t set;
    pid_t pid;
    int i, rc;
    short flags = POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETSIGMASK;

    argv = calloc((size_t)nargs + 1, sizeof *argv);
    if (argv == NULL) return -ENOMEM;
    for (i = 0; i < nargs; i++) {
        argv[i] = (char *)p;
        p += strlen(p) + 1;
    }
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    if (out[0] != '\0') {
        posix_spawn_file_actions_addopen(&actions, 1, out, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (err[0] == '\0') posix_spawn_file_actions_adddup2(&actions, 1, 2);
    }
    if (err[0] != '\0')
        posix_spawn_file_actions_addopen(&actions, 2, err, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawnattr_init(&attr);
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    posix_spawnattr_setsigdefault(&attr, &set);
    sigemptyset(&set);
    posix_spawnattr_setsigmask(&attr, &set);
    if (own_group) {
        flags |= POSIX_SPAWN_SETPGROUP;
        posix_spawnattr_setpgroup(&attr, 0);
    }
    posix_spawnattr_setflags(&attr, flags);
    rc = posix_spawnp(&pid, argv[0], &actions, &attr, argv, environ);
    posix_spawnattr_destroy(&attr);
    posix_spawn_file_actions_destroy(&actions);
    free(argv);
    return rc == 0 ? (int)pid : -rc;
}

/* Wait until one of the `n` children `pids` ends: its index (0-based),
 * with *code its exit status, or *signo the signal that ended it (the
 * other 0; *code -1 when it cannot be known). Returns -1 when `timeout_ms` (>= 0) passed first, and -2 when
 * `stop_on_signal` and SIGINT or SIGTERM has been caught (signals_shim.c).
 * Polls every 10 ms: a caught signal interrupts the sleep, and nothing
 * but these children is reaped. */
int flexmbs_process_wait_any(const int *pids, int n, int timeout_ms, int stop_on_signal,
                             int *code, int *signo)
{
    struct timespec pause = {0, 10000000L};
    long waited = 0;
    int i, st;
    pid_t rc;
    *code = 0;
    *signo = 0;
    for (;;) {
        for (i = 0; i < n; i++) {
            if (pids[i] <= 0) continue;
            rc = waitpid((pid_t)pids[i], &st, WNOHANG);
            if (rc == (pid_t)pids[i]) {
                if (WIFEXITED(st)) *code = WEXITSTATUS(st);
                else if (WIFSIGNALED(st)) *signo = WTERMSIG(st);
                return i;
            }
            if (rc < 0 && errno == ECHILD) { /* not ours, or reaped already */
                *code = -1;
                return i;
            }
        }
        if (stop_on_signal && flexmbs_signals_caught() != 0) return -2;
        if (timeout_ms >= 0 && waited >= timeout_ms) return -1;
        nanosleep(&pause, NULL);
        waited += 10;
    }
}

/* kill(2) of one child; 0 on success. */
int flexmbs_process_signal(int pid, int signo)
{
    return pid > 0 ? kill((pid_t)pid, signo) : -1;
}

/* The absolute path of this program's executable in `out` (size n): its
 * length, or -1. */
int flexmbs_process_self(char *out, int n)
{
    ssize_t len = readlink("/proc/self/exe", out, (size_t)n);
    if (len <= 0 || len >= n) return -1;
    out[len] = '\0';
    return (int)len;
}
