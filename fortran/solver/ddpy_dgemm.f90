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
