/* File identity for flexmbs_core_files: two paths name the same file when
 * they resolve to the same device and inode, however they are spelled
 * (./s.nml, ../in/s.nml, a link). */
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

/* The machine's physical memory in bytes, or -1 when unknown. */
long long flexmbs_physical_memory(void)
{
    long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGE_SIZE);
    if (pages <= 0 || size <= 0) return -1;
    return (long long)pages * (long long)size;
}
