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
