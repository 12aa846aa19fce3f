/* File identity for flexmbs_core_files: two paths name the same file when
 * they resolve to the same device and inode, however they are spelled
 * (./s.nml, ../in/s.nml, a link); a path not yet written resolves through
 * its folder. */
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* 1 when both paths exist and are the same file, 0 otherwise. */
int flexmbs_same_file(const char *a, const char *b)
{
    struct stat sa, sb;
    if (stat(a, &sa) != 0 || stat(b, &sb) != 0) return 0;
    return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

/* What `path` is: 0 missing, 1 regular file, 2 folder, 3 FIFO, 4 device,
 * 5 socket or other; *size its size in bytes (64 bits) for a regular file. */
int flexmbs_file_kind(const char *path, long long *size)
{
    struct stat s;
    *size = 0;
    if (stat(path, &s) != 0) return 0;
    if (S_ISREG(s.st_mode)) {
        *size = (long long)s.st_size;
        return 1;
    }
    if (S_ISDIR(s.st_mode)) return 2;
    if (S_ISFIFO(s.st_mode)) return 3;
    if (S_ISCHR(s.st_mode) || S_ISBLK(s.st_mode)) return 4;
    return 5;
}

#include <unistd.h>
#include <sys/resource.h>

/* The memory this process may use in bytes: the machine's physical memory,
 * or less when a resource limit (ulimit -v, -d) says so; -1 when unknown. */
long long flexmbs_physical_memory(void)
{
    long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGE_SIZE);
    long long bytes;
    struct rlimit lim;
    if (pages <= 0 || size <= 0) return -1;
    bytes = (long long)pages * (long long)size;
    if (getrlimit(RLIMIT_AS, &lim) == 0 && lim.rlim_cur != RLIM_INFINITY &&
        (long long)lim.rlim_cur < bytes) bytes = (long long)lim.rlim_cur;
    if (getrlimit(RLIMIT_DATA, &lim) == 0 && lim.rlim_cur != RLIM_INFINITY &&
        (long long)lim.rlim_cur < bytes) bytes = (long long)lim.rlim_cur;
    return bytes;
}

/* The absolute path without links, '.' or '..' in `out` (size n): the
 * file's own when it exists, else its folder's and its name. Its length,
 * or -1 when the folder does not exist or the result does not fit. */
int flexmbs_resolved_path(const char *path, char *out, int n)
{
    char buf[PATH_MAX], folder[PATH_MAX];
    const char *slash, *name;
    size_t len;
    if (realpath(path, buf) == NULL) {
        slash = strrchr(path, '/');
        if (slash == NULL) {
            strcpy(folder, ".");
            name = path;
        } else {
            len = (size_t)(slash - path);
            if (len == 0) len = 1; /* "/name" */
            if (len >= sizeof folder) return -1;
            memcpy(folder, path, len);
            folder[len] = '\0';
            name = slash + 1;
        }
        if (realpath(folder, buf) == NULL) return -1;
        len = strlen(buf);
        if (len + 1 + strlen(name) + 1 > sizeof buf) return -1;
        if (buf[len - 1] != '/') strcat(buf, "/");
        strcat(buf, name);
    }
    len = strlen(buf);
    if ((int)len >= n) return -1;
    memcpy(out, buf, len + 1);
    return (int)len;
}

/* mkdtemp(3): `path` ends in XXXXXX, replaced by the new folder's name
 * (a folder no one else has); 0 on success. */
int flexmbs_make_scratch_folder(char *path)
{
    return mkdtemp(path) == NULL ? -1 : 0;
}

#include <sys/statvfs.h>

/* Bytes an unprivileged user may still write in the file system holding
 * `folder`, or -1 when unknown. */
long long flexmbs_free_space(const char *folder)
{
    struct statvfs s;
    if (statvfs(folder, &s) != 0) return -1;
    return (long long)s.f_bavail * (long long)s.f_frsize;
}

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>

/* Write `n` bytes of `text` to `path` whole or not at all: into a new
 * temporary file beside it (mkstemp), flushed to the disk, then renamed
 * over `path` (rename(2) is atomic within a file system), so that a
 * reader, or a process killed meanwhile, sees the old file or the new one
 * and never a part. 0 on success, else the errno of the step that failed
 * (the temporary file removed). */
int flexmbs_write_atomically(const char *path, const char *text, long long n)
{
    size_t len = strlen(path);
    char *tmp = malloc(len + 16);
    int fd, rc = 0;
    long long done = 0;
    ssize_t wrote;
    if (tmp == NULL) return ENOMEM;
    memcpy(tmp, path, len);
    strcpy(tmp + len, ".tmp.XXXXXX");
    fd = mkstemp(tmp);
    if (fd < 0) {
        rc = errno;
        free(tmp);
        return rc;
    }
    while (done < n) {
        wrote = write(fd, text + done, (size_t)(n - done));
        if (wrote < 0) {
            if (errno == EINTR) continue;
            rc = errno;
            break;
        }
        done += wrote;
    }
    if (rc == 0 && fchmod(fd, 0644) != 0) rc = errno;
    if (rc == 0 && fsync(fd) != 0) rc = errno;
    if (close(fd) != 0 && rc == 0) rc = errno;
    if (rc == 0 && rename(tmp, path) != 0) rc = errno;
    if (rc != 0) unlink(tmp);
    free(tmp);
    return rc;
}

/* mkdir(2) with mode 0777 (less the umask); 0 when made or already a
 * folder, else errno. */
int flexmbs_make_folder(const char *path)
{
    struct stat s;
    int code;
    if (mkdir(path, 0777) == 0) return 0;
    code = errno;
    if (code == EEXIST && stat(path, &s) == 0 && S_ISDIR(s.st_mode)) return 0;
    return code;
}

/* The text of an errno value, in `out` (size n). */
void flexmbs_error_text(int code, char *out, int n)
{
    snprintf(out, (size_t)n, "%s", strerror(code));
}
