/* SIGINT and SIGTERM for flexmbs_core_signals: the handler only records
 * which signal came (a volatile sig_atomic_t, the one thing a handler may
 * safely write); the run polls it after every accepted step and stops
 * there, with its outputs flushed and closed.
 *
 * SA_RESETHAND puts the default action back after the first signal, so a
 * second Ctrl-C while the run is stopping ends the process at once.
 * SA_RESTART keeps interrupted system calls (file writes) going. A signal
 * that is ignored when the process starts (a background job of a
 * non-interactive shell ignores SIGINT, nohup ignores SIGHUP) is left
 * ignored, as the caller wants, unless told otherwise (the points of a
 * parallel sweep, whose shell ignores them so as to wait for every point). */
#include <signal.h>
#include <string.h>

static volatile sig_atomic_t caught = 0;

static void on_signal(int signo)
{
    if (caught == 0) caught = signo;
}

static int install(int signo, int even_if_ignored)
{
    struct sigaction old, sa;
    if (sigaction(signo, NULL, &old) != 0) return -1;
    if (old.sa_handler == SIG_IGN && !even_if_ignored) return 0;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESTART | SA_RESETHAND;
    return sigaction(signo, &sa, NULL);
}

/* Handlers for SIGINT and SIGTERM; 0 on success, -1 otherwise. */
int flexmbs_signals_install(int even_if_ignored)
{
    if (install(SIGINT, even_if_ignored) != 0) return -1;
    return install(SIGTERM, even_if_ignored);
}

/* The first signal caught, 0 while none. */
int flexmbs_signals_caught(void)
{
    return caught;
}

/* The numbers of SIGINT and SIGTERM on this system. */
int flexmbs_signals_sigint(void) { return SIGINT; }
int flexmbs_signals_sigterm(void) { return SIGTERM; }
