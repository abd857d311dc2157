!> The blank as the core keeps it: its mesh, element kind and material (blank_mesh, one per
!> ddpy.model.solid.Solid), and the numbering of its unknowns for one set of constraints
!> (blank_dofs, one per forming or static problem).
module ddpy_blank
  use ddpy_kinds, only: wp
  use ddpy_material, only: material_prop_count
  implicit none
  private
  public :: blank_mesh, blank_dofs

  !> The blank's mesh of ne 8-node elements of one kind (ddpy_solid_assembly: kind_*) on
  !> nnode nodes, and its material's properties (ddpy_material).
  type :: blank_mesh
    integer :: nnode = 0, ne = 0, kind = 0
    real(wp), allocatable :: x0(:, :)       !< (3, nnode) node coordinates
    integer, allocatable :: conn(:, :)      !< (8, ne) nodes of each element, 1-based
    real(wp) :: props(material_prop_count) = 0.0_wp
  end type blank_mesh

  !> The unknowns of the blank for one set of constraints: eqn(c, a) the 0-based equation of
  !> component c of node a (-1 where it is fixed), nf free dofs; the solid's tangent in the
  !> coordinate slots offsets(e) + 1 .. offsets(e + 1) of element e (ddpy_solid_assembly),
  !> k_slots of them, as its lower triangle when symmetric.
  type :: blank_dofs
    integer :: nf = 0, k_slots = 0
    logical :: symmetric = .false.
    integer, allocatable :: eqn(:, :)       !< (3, nnode)
    logical, allocatable :: fixed(:, :)     !< (3, nnode): eqn < 0
    integer, allocatable :: offsets(:)      !< (ne + 1), 0-based
  end type blank_dofs

end module ddpy_blank
