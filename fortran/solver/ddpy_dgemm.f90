!> DGEMM for MUMPS: a matrix-vector product (one column, n = 1) goes to DGEMV, every other
!> product to the BLAS's own DGEMM (through cblas_dgemm, which does not come back here).
!>
!> MUMPS solves with one right-hand side by multiplying each front's factor blocks with one
!> column through DGEMM. Debian 12's OpenBLAS (0.3.21) treats that as a matrix product: it
!> packs the factor block into its buffers first and then multiplies, about 1.6 us a call,
!> and a solve with the paper bending blank's factors makes tens of thousands of such
!> calls. As DGEMV the same products read the block once, and the solves of a Newton
!> iteration take about a fifth less time (docs/theory/linear-solver.md, "The single-vector
!> products").
!>
!> SGEMM does the same for the single-precision factors (ddpy_linear_solver's precision).
!>
!> DTRSM and STRSM: a triangular solve with one column (the diagonal block of each front in
!> a solve) goes to DTRSV / STRSV for the same reason. OpenBLAS packs the triangle before
!> solving, which on a small blank's fronts costs more than the solve itself
!> (docs/theory/linear-solver.md, "The single-vector products").
!>
!> These are external procedures, not a module's, on purpose: linked into the core, each is
!> the one the core's MUMPS finds first (the core's shared object comes before its
!> libraries in their symbol lookup), so it stands in for the BLAS's entry point.
subroutine dgemm(transa, transb, m, n, k, alpha, a, lda, b, ldb, beta, c, ldc)
  use, intrinsic :: iso_c_binding, only: c_int, c_double
  implicit none
  character, intent(in) :: transa, transb
  integer, intent(in) :: m, n, k, lda, ldb, ldc
  real(c_double), intent(in) :: alpha, beta
  real(c_double), intent(in) :: a(*), b(*)
  real(c_double), intent(inout) :: c(*)
  integer(c_int), parameter :: col_major = 102, no_trans = 111, trans = 112
  interface
    subroutine cblas_dgemm(order, ta, tb, m, n, k, alpha, a, lda, b, ldb, beta, c, ldc) &
        bind(c, name='cblas_dgemm')
      import :: c_int, c_double
      integer(c_int), value :: order, ta, tb, m, n, k, lda, ldb, ldc
      real(c_double), value :: alpha, beta
      real(c_double), intent(in) :: a(*), b(*)
      real(c_double), intent(inout) :: c(*)
    end subroutine cblas_dgemm
  end interface
  external :: dgemv
  logical :: a_transposed, b_transposed
  a_transposed = transa /= 'N' .and. transa /= 'n'
  b_transposed = transb /= 'N' .and. transb /= 'n'
  ! Only B untransposed, the products MUMPS makes; k = 0 stays with DGEMM, since DGEMV
  ! would return without scaling c by beta.
  if (n == 1 .and. m > 0 .and. k > 0 .and. .not. b_transposed) then
    if (a_transposed) then
      call dgemv('T', k, m, alpha, a, lda, b, 1, beta, c, 1)
    else
      call dgemv('N', m, k, alpha, a, lda, b, 1, beta, c, 1)
    end if
    return
  end if
  call cblas_dgemm(col_major, merge(trans, no_trans, a_transposed), &
                   merge(trans, no_trans, b_transposed), m, n, k, alpha, a, lda, b, ldb, &
                   beta, c, ldc)
end subroutine dgemm

subroutine sgemm(transa, transb, m, n, k, alpha, a, lda, b, ldb, beta, c, ldc)
  use, intrinsic :: iso_c_binding, only: c_int, c_float
  implicit none
  character, intent(in) :: transa, transb
  integer, intent(in) :: m, n, k, lda, ldb, ldc
  real(c_float), intent(in) :: alpha, beta
  real(c_float), intent(in) :: a(*), b(*)
  real(c_float), intent(inout) :: c(*)
  integer(c_int), parameter :: col_major = 102, no_trans = 111, trans = 112
  interface
    subroutine cblas_sgemm(order, ta, tb, m, n, k, alpha, a, lda, b, ldb, beta, c, ldc) &
        bind(c, name='cblas_sgemm')
      import :: c_int, c_float
      integer(c_int), value :: order, ta, tb, m, n, k, lda, ldb, ldc
      real(c_float), value :: alpha, beta
      real(c_float), intent(in) :: a(*), b(*)
      real(c_float), intent(inout) :: c(*)
    end subroutine cblas_sgemm
  end interface
  external :: sgemv
  logical :: a_transposed, b_transposed
  a_transposed = transa /= 'N' .and. transa /= 'n'
  b_transposed = transb /= 'N' .and. transb /= 'n'
  ! Only B untransposed, the products MUMPS makes; k = 0 stays with DGEMM, since DGEMV
  ! would return without scaling c by beta.
  if (n == 1 .and. m > 0 .and. k > 0 .and. .not. b_transposed) then
    if (a_transposed) then
      call sgemv('T', k, m, alpha, a, lda, b, 1, beta, c, 1)
    else
      call sgemv('N', m, k, alpha, a, lda, b, 1, beta, c, 1)
    end if
    return
  end if
  call cblas_sgemm(col_major, merge(trans, no_trans, a_transposed), &
                   merge(trans, no_trans, b_transposed), m, n, k, alpha, a, lda, b, ldb, &
                   beta, c, ldc)
end subroutine sgemm

subroutine dtrsm(side, uplo, transa, diag, m, n, alpha, a, lda, b, ldb)
  use, intrinsic :: iso_c_binding, only: c_int, c_double
  implicit none
  character, intent(in) :: side, uplo, transa, diag
  integer, intent(in) :: m, n, lda, ldb
  real(c_double), intent(in) :: alpha
  real(c_double), intent(in) :: a(*)
  real(c_double), intent(inout) :: b(*)
  interface
    subroutine cblas_dtrsm(order, side, uplo, ta, diag, m, n, alpha, a, lda, b, ldb) &
        bind(c, name='cblas_dtrsm')
      import :: c_int, c_double
      integer(c_int), value :: order, side, uplo, ta, diag, m, n, lda, ldb
      real(c_double), value :: alpha
      real(c_double), intent(in) :: a(*)
      real(c_double), intent(inout) :: b(*)
    end subroutine cblas_dtrsm
  end interface
  external :: dtrsv
  ! CBLAS's codes: column major 102; left 141, right 142; upper 121, lower 122; no
  ! transpose 111, transpose 112; non-unit 131, unit 132.
  ! One column on the left, op(A) x = alpha b: the vector solve on alpha b.
  if (n == 1 .and. m > 0 .and. (side == 'L' .or. side == 'l')) then
    if (alpha == 0) then
      b(1:m) = 0
      return
    end if
    if (alpha /= 1) b(1:m) = alpha * b(1:m)
    call dtrsv(uplo, transa, diag, m, a, lda, b, 1)
    return
  end if
  call cblas_dtrsm(102_c_int, merge(141_c_int, 142_c_int, side == 'L' .or. side == 'l'), &
                   merge(121_c_int, 122_c_int, uplo == 'U' .or. uplo == 'u'), &
                   merge(111_c_int, 112_c_int, transa == 'N' .or. transa == 'n'), &
                   merge(132_c_int, 131_c_int, diag == 'U' .or. diag == 'u'), m, n, alpha, a, &
                   lda, b, ldb)
end subroutine dtrsm

subroutine strsm(side, uplo, transa, diag, m, n, alpha, a, lda, b, ldb)
  use, intrinsic :: iso_c_binding, only: c_int, c_float
  implicit none
  character, intent(in) :: side, uplo, transa, diag
  integer, intent(in) :: m, n, lda, ldb
  real(c_float), intent(in) :: alpha
  real(c_float), intent(in) :: a(*)
  real(c_float), intent(inout) :: b(*)
  interface
    subroutine cblas_strsm(order, side, uplo, ta, diag, m, n, alpha, a, lda, b, ldb) &
        bind(c, name='cblas_strsm')
      import :: c_int, c_float
      integer(c_int), value :: order, side, uplo, ta, diag, m, n, lda, ldb
      real(c_float), value :: alpha
      real(c_float), intent(in) :: a(*)
      real(c_float), intent(inout) :: b(*)
    end subroutine cblas_strsm
  end interface
  external :: strsv
  ! CBLAS's codes: column major 102; left 141, right 142; upper 121, lower 122; no
  ! transpose 111, transpose 112; non-unit 131, unit 132.
  ! One column on the left, op(A) x = alpha b: the vector solve on alpha b.
  if (n == 1 .and. m > 0 .and. (side == 'L' .or. side == 'l')) then
    if (alpha == 0) then
      b(1:m) = 0
      return
    end if
    if (alpha /= 1) b(1:m) = alpha * b(1:m)
    call strsv(uplo, transa, diag, m, a, lda, b, 1)
    return
  end if
  call cblas_strsm(102_c_int, merge(141_c_int, 142_c_int, side == 'L' .or. side == 'l'), &
                   merge(121_c_int, 122_c_int, uplo == 'U' .or. uplo == 'u'), &
                   merge(111_c_int, 112_c_int, transa == 'N' .or. transa == 'n'), &
                   merge(132_c_int, 131_c_int, diag == 'U' .or. diag == 'u'), m, n, alpha, a, &
                   lda, b, ldb)
end subroutine strsm
