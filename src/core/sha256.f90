!> SHA-256 of a text (FIPS 180-4, section 6.2), as 64 lower-case hex
!> digits: the fingerprint a sweep's records carry of the study, scene and
!> mesh files they were computed from (run/study_record).
!>
!> The 32-bit words are held in 64-bit integers and masked after every
!> addition, so no operation overflows (Fortran has no unsigned type).
module flexmbs_core_sha256
    use, intrinsic :: iso_fortran_env, only: int64
    implicit none
    private

    public :: sha256_hex

    integer(int64), parameter :: mask32 = int(z'FFFFFFFF', int64)
    !> The first 32 bits of the fractional parts of the cube roots of the
    !> first 64 primes (FIPS 180-4, 4.2.2).
    integer(int64), parameter :: k(0:63) = [ &
        int(z'428a2f98', int64), int(z'71374491', int64), int(z'b5c0fbcf', int64), &
        int(z'e9b5dba5', int64), int(z'3956c25b', int64), int(z'59f111f1', int64), &
        int(z'923f82a4', int64), int(z'ab1c5ed5', int64), int(z'd807aa98', int64), &
        int(z'12835b01', int64), int(z'243185be', int64), int(z'550c7dc3', int64), &
        int(z'72be5d74', int64), int(z'80deb1fe', int64), int(z'9bdc06a7', int64), &
        int(z'c19bf174', int64), int(z'e49b69c1', int64), int(z'efbe4786', int64), &
        int(z'0fc19dc6', int64), int(z'240ca1cc', int64), int(z'2de92c6f', int64), &
        int(z'4a7484aa', int64), int(z'5cb0a9dc', int64), int(z'76f988da', int64), &
        int(z'983e5152', int64), int(z'a831c66d', int64), int(z'b00327c8', int64), &
        int(z'bf597fc7', int64), int(z'c6e00bf3', int64), int(z'd5a79147', int64), &
        int(z'06ca6351', int64), int(z'14292967', int64), int(z'27b70a85', int64), &
        int(z'2e1b2138', int64), int(z'4d2c6dfc', int64), int(z'53380d13', int64), &
        int(z'650a7354', int64), int(z'766a0abb', int64), int(z'81c2c92e', int64), &
        int(z'92722c85', int64), int(z'a2bfe8a1', int64), int(z'a81a664b', int64), &
        int(z'c24b8b70', int64), int(z'c76c51a3', int64), int(z'd192e819', int64), &
        int(z'd6990624', int64), int(z'f40e3585', int64), int(z'106aa070', int64), &
        int(z'19a4c116', int64), int(z'1e376c08', int64), int(z'2748774c', int64), &
        int(z'34b0bcb5', int64), int(z'391c0cb3', int64), int(z'4ed8aa4a', int64), &
        int(z'5b9cca4f', int64), int(z'682e6ff3', int64), int(z'748f82ee', int64), &
        int(z'78a5636f', int64), int(z'84c87814', int64), int(z'8cc70208', int64), &
        int(z'90befffa', int64), int(z'a4506ceb', int64), int(z'bef9a3f7', int64), &
        int(z'c67178f2', int64)]
    !> The initial hash value (FIPS 180-4, 5.3.3).
    integer(int64), parameter :: h0(0:7) = [ &
        int(z'6a09e667', int64), int(z'bb67ae85', int64), int(z'3c6ef372', int64), &
        int(z'a54ff53a', int64), int(z'510e527f', int64), int(z'9b05688c', int64), &
        int(z'1f83d9ab', int64), int(z'5be0cd19', int64)]

contains

    !> The SHA-256 digest of the bytes of `text`, in hex.
    function sha256_hex(text) result(hex)
        character(len=*), intent(in) :: text
        character(len=64) :: hex
        character(len=*), parameter :: digits = '0123456789abcdef'
        integer(int64) :: h(0:7), bits
        integer :: block(0:63), tail(0:127), nfull, rest, ntail, i, j, nibble
        h = h0
        nfull = len(text) / 64
        do i = 0, nfull - 1
            do j = 0, 63
                block(j) = ichar(text(64 * i + j + 1:64 * i + j + 1))
            end do
            call compress(h, block)
        end do
        ! the padding: the rest, a 1 bit, zeros, and the length in bits
        ! (big-endian, 64 bits) ending a block
        rest = len(text) - 64 * nfull
        tail = 0
        do j = 0, rest - 1
            tail(j) = ichar(text(64 * nfull + j + 1:64 * nfull + j + 1))
        end do
        tail(rest) = 128
        ntail = merge(64, 128, rest < 56)
        bits = 8_int64 * len(text, int64)
        do j = 0, 7
            tail(ntail - 1 - j) = int(iand(ishft(bits, -8 * j), 255_int64))
        end do
        call compress(h, tail(0:63))
        if (ntail == 128) call compress(h, tail(64:127))
        do i = 0, 7
            do j = 0, 7
                nibble = int(iand(ishft(h(i), -(28 - 4 * j)), 15_int64))
                hex(8 * i + j + 1:8 * i + j + 1) = digits(nibble + 1:nibble + 1)
            end do
        end do
    end function sha256_hex

    !> One 64-byte block into the hash value (FIPS 180-4, 6.2.2).
    pure subroutine compress(h, block)
        integer(int64), intent(inout) :: h(0:7)
        integer, intent(in) :: block(0:63) !! bytes, 0..255
        integer(int64) :: w(0:63), a, b, c, d, e, f, g, hh, t1, t2
        integer :: t
        do t = 0, 15
            w(t) = ior(ior(ishft(int(iand(block(4 * t), 255), int64), 24), &
                           ishft(int(iand(block(4 * t + 1), 255), int64), 16)), &
                       ior(ishft(int(iand(block(4 * t + 2), 255), int64), 8), &
                           int(iand(block(4 * t + 3), 255), int64)))
        end do
        do t = 16, 63
            w(t) = add(add(small_sigma1(w(t - 2)), w(t - 7)), add(small_sigma0(w(t - 15)), &
                                                                   w(t - 16)))
        end do
        a = h(0); b = h(1); c = h(2); d = h(3); e = h(4); f = h(5); g = h(6); hh = h(7)
        do t = 0, 63
            t1 = add(add(add(hh, big_sigma1(e)), add(choose(e, f, g), k(t))), w(t))
            t2 = add(big_sigma0(a), majority(a, b, c))
            hh = g; g = f; f = e
            e = add(d, t1)
            d = c; c = b; b = a
            a = add(t1, t2)
        end do
        h = iand(h + [a, b, c, d, e, f, g, hh], mask32)
    end subroutine compress

    pure integer(int64) function add(x, y)
        integer(int64), intent(in) :: x, y
        add = iand(x + y, mask32)
    end function add

    pure integer(int64) function rotr(x, n)
        integer(int64), intent(in) :: x
        integer, intent(in) :: n
        rotr = iand(ior(ishft(x, -n), ishft(x, 32 - n)), mask32)
    end function rotr

    pure integer(int64) function choose(x, y, z)
        integer(int64), intent(in) :: x, y, z
        choose = ieor(iand(x, y), iand(ieor(x, mask32), z))
    end function choose

    pure integer(int64) function majority(x, y, z)
        integer(int64), intent(in) :: x, y, z
        majority = ieor(ieor(iand(x, y), iand(x, z)), iand(y, z))
    end function majority

    pure integer(int64) function big_sigma0(x)
        integer(int64), intent(in) :: x
        big_sigma0 = ieor(ieor(rotr(x, 2), rotr(x, 13)), rotr(x, 22))
    end function big_sigma0

    pure integer(int64) function big_sigma1(x)
        integer(int64), intent(in) :: x
        big_sigma1 = ieor(ieor(rotr(x, 6), rotr(x, 11)), rotr(x, 25))
    end function big_sigma1

    pure integer(int64) function small_sigma0(x)
        integer(int64), intent(in) :: x
        small_sigma0 = ieor(ieor(rotr(x, 7), rotr(x, 18)), ishft(x, -3))
    end function small_sigma0

    pure integer(int64) function small_sigma1(x)
        integer(int64), intent(in) :: x
        small_sigma1 = ieor(ieor(rotr(x, 17), rotr(x, 19)), ishft(x, -10))
    end function small_sigma1
end module flexmbs_core_sha256
