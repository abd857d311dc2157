!> Sparse matrix helpers of the Newton loop.
!>
!> The assembly writes the Jacobian as coordinates with duplicates (one entry per element
!> contribution, so that threads never write to the same place). The products of the Krylov
!> solver need it with the duplicates summed, once per GMRES call: on the paper's bending
!> blank 11.7 million coordinates into 5.7 million entries. Every entry gathers its own
!> contributions (ddpy.core.linalg.row_structure lists them), in parallel; a scatter over
!> the coordinates would run on one thread.
module ddpy_sparse
  use ddpy_kinds, only: wp
  implicit none
  private
  public :: sum_duplicates, row_structure, rows_fit

  !> The Jacobian's coordinates summed by rows (ddpy.core.linalg.row_structure), for the
  !> products of GMRES: row i's entries are row_start(i) + 1 .. row_start(i + 1), each in
  !> column col (0-based), the sum of the coordinate values at sources(source_start(k) +
  !> 1 .. source_start(k + 1)) (0-based). n = 0: none given (no Krylov solves).
  type :: row_structure
    integer :: n = 0
    integer, allocatable :: row_start(:), col(:), sources(:), source_start(:)
  end type row_structure

contains

  !> Whether a row structure of n rows over nvalues coordinate values is in order: rows
  !> and sources from 0 to their counts, columns in 0..n-1, sources in 0..nvalues-1.
  pure logical function rows_fit(n, ncsr, nsrc, nvalues, row_start, col, sources, &
                                 source_start) result(ok)
    integer, intent(in) :: n, ncsr, nsrc, nvalues, row_start(n + 1), col(ncsr), &
                           sources(nsrc), source_start(ncsr + 1)
    ok = row_start(1) == 0 .and. row_start(n + 1) == ncsr .and. &
         all(row_start(2:) >= row_start(:n)) .and. source_start(1) == 0 .and. &
         source_start(ncsr + 1) == nsrc .and. all(source_start(2:) >= source_start(:ncsr)) &
         .and. all(col >= 0 .and. col < n) .and. all(sources >= 0 .and. sources < nvalues)
  end function rows_fit

  !> data(i) = sum of values(sources(k) + 1) over k = starts(i) + 1 .. starts(i + 1):
  !> sources lists, entry after entry, the 0-based positions of each entry's contributions.
  subroutine sum_duplicates(n_values, n_data, values, sources, starts, data)
    integer, intent(in) :: n_values, n_data
    real(wp), intent(in) :: values(n_values)
    integer, intent(in) :: sources(*), starts(n_data + 1)
    real(wp), intent(out) :: data(n_data)
    integer :: i, k
    real(wp) :: total
    !$omp parallel do schedule(static) private(k, total)
    do i = 1, n_data
      total = 0.0_wp
      do k = starts(i) + 1, starts(i + 1)
        total = total + values(sources(k) + 1)
      end do
      data(i) = total
    end do
    !$omp end parallel do
  end subroutine sum_duplicates

end module ddpy_sparse
